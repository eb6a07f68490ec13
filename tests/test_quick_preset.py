"""The quick preset runs the study, not benchmarks of the code's own speed; `make bench` runs those.

A benchmark of the code is a rule whose command runs a ``*benchmark*`` module or tools/ script
(the batched integrator against a loop, every calibration set with two integrators, the DEM
stage against bare YADE): it measures the code, not the physics. The quick preset's dry run (in
a working copy of its own) must plan none of them and every part of the study; the Makefile's
``bench`` command must plan all of them.
"""
import re
import shlex

import pytest
import yaml

from tests.helpers import ROOT, counts, dry_run, workflow_rules

#: Rules of the study the quick preset must keep (DEM, calibration, comparison, claims, and
#: what accuracy costs in the study itself: the ODE work-precision and the packing's share).
STUDY = {"dem_pack", "dem_preshear", "dem_reversal", "calibrate", "compare_predict", "claims",
         "ode_work_precision", "packing_cost", "claims_table_html", "packing_table_html", "calibration_tables_html"}


@pytest.fixture(scope="module")
def code_benchmarks(module_workflow_dir):
    """Rule names whose shell command runs a module or a tools/ script named ``*benchmark*``."""
    rules = workflow_rules(module_workflow_dir, module_workflow_dir / "config" / "quick.yaml")
    names = {rule.name for rule in rules
             if rule.shellcmd and re.search(r"-m \w+(\.\w+)*benchmark\b|tools/\w*benchmark\.py\b", rule.shellcmd)}
    assert {"batched_cost", "calibration_cost", "stage_overhead"} <= names, names  # else the definition found nothing
    return names


def bench_command():
    """The arguments of the Makefile's `bench` recipe after `snakemake` (its Snakemake line; the pre-flight
    comes first), its variables expanded."""
    text = (ROOT / "Makefile").read_text()
    variables = dict(re.findall(r"^(\w+)\s*:=\s*(.*)$", text, re.M))
    lines = re.search(r"^bench:.*\n((?:\t.*\n?)+)", text, re.M).group(1).splitlines()
    recipe = next(line.strip() for line in lines if "/snakemake " in line)
    recipe = re.sub(r"\$\((\w+)\)", lambda m: variables[m.group(1)], recipe)
    words = shlex.split(recipe)
    return words[words.index(next(w for w in words if w.endswith("snakemake"))) + 1:]


def test_the_quick_preset_plans_the_study_and_no_benchmark_of_the_code(code_benchmarks, shared_dry_run):
    result = shared_dry_run("--configfile", "config/quick.yaml")
    assert result.returncode == 0, result.stderr[-3000:]
    jobs = counts(result.stdout)
    assert not code_benchmarks & set(jobs), sorted(code_benchmarks & set(jobs))
    assert STUDY <= set(jobs), sorted(STUDY - set(jobs))


def test_snakemake_finds_the_workflow_profile_that_runs_run_blocks_in_its_own_threads(shared_dry_run):
    """A ``run:`` job (scene files, HTML tables) in a new Snakemake process parses the workflow and
    runs the pre-flight again: 3-4 s each instead of about 0.1 s (profiles/default/config.yaml)."""
    result = shared_dry_run("--configfile", "config/quick.yaml")
    assert "Using workflow specific profile profiles/default" in result.stdout + result.stderr
    profile = yaml.safe_load((ROOT / "profiles" / "default" / "config.yaml").read_text())
    assert profile["force-use-threads"] is True


def test_make_bench_plans_every_benchmark_of_the_code(code_benchmarks, workflow_dir):
    args = bench_command()
    assert "config/quick.yaml" in args
    result = dry_run(*[a for a in args if a != "-j2"], cwd=workflow_dir)
    assert result.returncode == 0, result.stderr[-3000:]
    assert code_benchmarks <= set(counts(result.stdout)), counts(result.stdout)


def planned_priorities(stdout):
    """(rule, wildcards) -> priority, from a verbose dry run's job blocks (a job without a priority: 0)."""
    jobs = []
    for line in stdout.splitlines():
        head = re.match(r"^(?:local)?rule (\w+):", line)
        if head:
            jobs.append([head.group(1), "", 0])
        elif jobs and line.strip().startswith("wildcards:"):
            jobs[-1][1] = line.split(":", 1)[1].strip()
        elif jobs and line.strip().startswith("priority:"):
            jobs[-1][2] = int(float(line.split(":", 1)[1]))
    return {(rule, wildcards): priority for rule, wildcards, priority in jobs}


def test_the_quick_preset_runs_the_dem_longest_chain_first_then_the_largest_calibration_set(shared_dry_run):
    """On 2 cores no long job should end the study alone: the DEM (it gates every set but the per-I
    ones) before anything else, the I = 2e-3 chains before the 3 times cheaper I = 5e-3 ones, then
    the set "all" (the largest) before the others."""
    result = shared_dry_run("--configfile", "config/quick.yaml", quiet=False)
    assert result.returncode == 0, result.stderr[-3000:]
    prio = planned_priorities(result.stdout)
    dem = {k: v for k, v in prio.items() if k[0] in ("scene", "dem_pack", "dem_preshear", "dem_reversal")}
    rest = {k: v for k, v in prio.items() if k not in dem}
    assert len(dem) == 30 and min(dem.values()) > max(rest.values()), (dem, rest)
    assert prio[("scene", "case=p100000_I0.002_s1")] > prio[("scene", "case=p100000_I0.005_s1")]
    assert prio[("dem_preshear", "case=p100000_I0.002_s1")] > prio[("dem_preshear", "case=p100000_I0.005_s1")]
    assert prio[("dem_pack", "case=p100000_I0.002_s1")] > prio[("dem_preshear", "case=p100000_I0.002_s1")]
    sets = {k[1].split("=")[1]: v for k, v in prio.items() if k[0] == "calibrate"}
    assert max(sets, key=sets.get) == "all" and sets["heaviside_only"] > sets["I0.005"], sets
