"""The SLURM profile: every job gets a runtime and memory, also with the README's command line.

The dry runs here touch no cluster (``-n``: Snakemake's dry-run executor).
``test_ci_preset_runs_through_a_local_slurm`` runs the CI preset on a real
one-node Slurm (workflow/scripts/slurm_local.sh) and is opt-in: marker
``slurm``, run with ``RUN_SLURM=1 .venv/bin/python -m pytest -m slurm``
(root, about 10 minutes).
"""
import math
import os
import re
import subprocess
import sys
import time

import pytest

from campaign import cost
from tests.helpers import ROOT, SNAKEMAKE, workflow_copy

README_ARGS = ["--default-resources", "slurm_account=ACCOUNT", "slurm_partition=PARTITION"]
LOCAL_RULES = {"all", "scene", "dem_study_scene", "dem_study_points"}


def planned_resources(shared_dry_run, *args):
    """rule -> list of resource dicts, one per planned job, from a dry run (``shared_dry_run``: the
    profile's own is planned once for the tests here and tests/test_workflow.py)."""
    result = shared_dry_run("--profile", "profiles/slurm", *args, quiet=False)
    assert result.returncode == 0, result.stderr[-3000:]
    jobs, rule = {}, None
    for line in (result.stdout + result.stderr).splitlines():
        if m := re.match(r"^(?:local)?rule (\w+):", line):
            rule = m.group(1)
            jobs.setdefault(rule, [])
        elif rule and (m := re.match(r"^\s+resources: (.*)$", line)):
            jobs[rule].append(dict(kv.split("=", 1) for kv in m.group(1).split(", ")))
    return jobs


@pytest.mark.parametrize("extra", [[], README_ARGS], ids=["profile", "readme-command"])
def test_every_cluster_job_gets_a_runtime_and_memory(extra, shared_dry_run):
    jobs = planned_resources(shared_dry_run, *extra)
    assert "dem_preshear" in jobs and "dem_study_preshear" in jobs, sorted(jobs)
    for rule, planned in jobs.items():
        if rule in LOCAL_RULES:
            continue
        for res in planned:
            assert int(res.get("runtime", 0)) > 0 and int(res.get("mem_mb", 0)) >= 1000, (rule, res)
    if extra:
        assert all(res["slurm_account"] == "ACCOUNT" for res in jobs["dem_preshear"])


def test_dem_runtime_follows_the_scene_not_a_flat_default(shared_dry_run):
    jobs = planned_resources(shared_dry_run)
    preshear = [int(res["runtime"]) for res in jobs["dem_preshear"]]
    # the paper cell: about 5,000 disks at kappa 700 and I 3e-4, about 35 min per unit strain by the cost
    # model (measured 29-30 under load, docs/findings.md "The reconciled physics"), a 2-strain pre-shear: 70 min x 3
    assert min(preshear) > 3 * 60, preshear
    study = sorted(int(res["runtime"]) for res in jobs["dem_study_preshear"])
    assert study[0] < study[-1] / 5, study  # the study's cheap and dear points differ


def test_a_lammps_stages_slurm_runtime_comes_from_lammps_throughput(shared_dry_run):
    """The same campaign with ``engine: lammps``: each DEM job's runtime, ceil(DEM_SAFETY seconds / 60 + 2)
    (workflow/rules/resources.smk), has its projected seconds divided by LAMMPS_OVER_YADE (campaign/cost.py)."""
    yade = planned_resources(shared_dry_run)
    lammps = planned_resources(shared_dry_run, "--config", "engine=lammps")
    overhead = 2   # DEM_OVERHEAD_MIN
    for rule in ("dem_pack", "dem_preshear", "dem_reversal", "dem_study_preshear"):
        pairs = list(zip(*(sorted(int(r["runtime"]) for r in jobs[rule]) for jobs in (yade, lammps))))
        assert pairs and len(pairs) == len(yade[rule]) == len(lammps[rule]), rule
        for y, m in pairs:
            # YADE's y = ceil(x + overhead) puts x = DEM_SAFETY seconds / 60 in (y - 1 - overhead, y - overhead];
            # LAMMPS's is ceil(x / LAMMPS_OVER_YADE + overhead)
            x_low, x_high = y - 1 - overhead, y - overhead
            assert (math.ceil(x_low / cost.LAMMPS_OVER_YADE + overhead) <= m
                    <= math.ceil(x_high / cost.LAMMPS_OVER_YADE + overhead)), (rule, y, m)
    longest = [max(int(r["runtime"]) for r in jobs["dem_preshear"]) for jobs in (yade, lammps)]
    assert longest[1] < longest[0] / 3, longest


RUN_SLURM = os.environ.get("RUN_SLURM") == "1"


@pytest.mark.slurm
@pytest.mark.serial  # a Slurm daemon on this machine
@pytest.mark.skipif(not RUN_SLURM, reason="opt-in: RUN_SLURM=1 (root; installs and starts a local Slurm)")
def test_ci_preset_runs_through_a_local_slurm(tmp_path):
    script = ROOT / "workflow/scripts/slurm_local.sh"
    was_up = subprocess.run([script, "status"], capture_output=True, text=True).stdout.startswith(
        "slurmctld: running")
    if not was_up:
        subprocess.run([script, "up"], check=True, timeout=900)
    results = tmp_path / "results"
    workdir = workflow_copy(tmp_path / "workflow")  # its .snakemake/ (and slurm_logs/) its own
    smk = [*SNAKEMAKE, "--configfile", "config/ci.yaml", "--config", f"results_dir={results}",
           "allow_outside_tree=True"]
    try:
        t0 = time.monotonic()
        run = subprocess.run([*smk, "--profile", "profiles/slurm", "--slurm-logdir", str(tmp_path / "slurm")],
                             cwd=workdir, capture_output=True, text=True, timeout=3600)
        wall = time.monotonic() - t0
        assert run.returncode == 0, run.stderr[-4000:]
        print(f"CI preset through the local Slurm: {wall:.0f} s")
        subprocess.run([*smk, "--report", str(results / "report.html")], cwd=workdir, check=True, timeout=600)
        summary = subprocess.run([*smk, "--summary"], cwd=workdir, capture_output=True, text=True, check=True)
        (results / "summary.tsv").write_text(summary.stdout)
        check = subprocess.run(
            [sys.executable, "workflow/scripts/check_outputs.py", results / "summary.tsv",
             results / "report.html", "--results", results],
            cwd=ROOT, capture_output=True, text=True)
        assert check.returncode == 0, check.stdout[-3000:] + check.stderr[-3000:]
    finally:
        if not was_up:
            subprocess.run([script, "down"], check=False)
