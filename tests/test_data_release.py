"""A data release (docs/data-release.md): made from a finished campaign, verified, and used in place of its DEM.

A small real campaign (the CI preset's physics on a 6 x 12 d cell of 56 disks,
three seeds, Heaviside and sinusoidal reversals: about 10 s of YADE, a minute
with its calibration, comparison and claims) is run once through Snakemake and
released with ``python -m dem_contract release`` into a temporary folder. The
tests then check the release's checksums and contract, restore its cases,
recompute the claims from the release alone and dry-run a campaign with one
more seed. The committed releases (``data/*/manifest.yaml``) are checked by
``test_committed_release_checksums_and_contract_hold`` in the normal suite;
``test_released_case_dem_reruns_identically`` (opt-in: ``RUN_RELEASE_DEM=1``)
re-runs one released case's DEM from its manifest.
"""
import filecmp
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
import yaml

from dem_contract import DEMInputError, published, read_series, release, synthetic
from dem_contract.importer import import_cases
from model import default_params
from tests.helpers import counts, dry_run, snakemake

ROOT = Path(__file__).resolve().parents[1]
DEM_RULES = ("scene", "dem_pack", "dem_preshear", "dem_reversal")
SEEDS = [1, 2, 3]
COMMITTED = sorted(p.parent for p in (ROOT / "data").glob("*/manifest.yaml"))
RUN_RELEASE_DEM = os.environ.get("RUN_RELEASE_DEM") == "1"


def campaign_config(results_dir, seeds=SEEDS, **extra):
    """The CI preset on a smaller cell (calibration, comparison and claims still run), no accuracy studies."""
    config = yaml.safe_load((ROOT / "config" / "ci.yaml").read_text())
    config.update(results_dir=str(results_dir), allow_outside_tree=True,  # (pytest's tmp_path)
                  seeds=list(seeds), cell={"H_over_d": 6, "W_over_H": 2},
                  accuracy={"ode_work_precision": False, "batched_cost": False, "calibration_cost": False,
                            "dem_study": False}, **extra)
    return config


def write(config, path):
    path.write_text(yaml.safe_dump(config))
    return path


def planned_jobs(stdout) -> dict:
    """Rule -> job count from a dry run's job table."""
    counts = {}
    for line in stdout.splitlines():
        parts = line.split()
        if len(parts) == 2 and parts[1].isdigit() and parts[0] != "total":
            counts[parts[0]] = int(parts[1])
    return counts


@pytest.fixture(scope="module")
def released(tmp_path_factory, module_workflow_dir):
    """The finished campaign (through its claims) and its release: (config path, results, release folder)."""
    if shutil.which("yade") is None:
        pytest.skip("needs YADE (Debian package yade)")
    tmp = tmp_path_factory.mktemp("release")
    results = tmp / "results"
    config = write(campaign_config(results), tmp / "config.yaml")
    run = snakemake("-j1", results / "claims" / "paper_claims.csv", "--configfile", config, "--quiet",
                    cwd=module_workflow_dir, timeout=900)
    assert run.returncode == 0, run.stderr[-3000:]
    out = tmp / "data" / "tiny"
    made = subprocess.run([sys.executable, "-m", "dem_contract", "release", "--cases",
                           *sorted(map(str, (results / "dem").glob("p*"))), "--config", str(config), "--out", str(out),
                           "--states", "--published", str(results / "claims" / "paper_claims.csv")],
                          cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert made.returncode == 0, made.stderr
    assert "budget 20 MB" in made.stdout
    return config, results, out


@pytest.mark.parametrize("folder", COMMITTED, ids=[p.name for p in COMMITTED])
def test_committed_release_checksums_and_contract_hold(folder):
    """Every committed release: each file's sha256 as in its manifest, every case read back by the contract."""
    assert release.verify(folder) == []


def test_committed_releases_fit_the_size_budget():
    """All releases together at most 20 MB in the repository (issue 26's budget)."""
    if not COMMITTED:
        pytest.skip("no release committed under data/")
    assert release.release_bytes(ROOT / "data") <= 20e6


def test_code_and_data_licenses_are_named_in_the_citation_and_every_release():
    """GPL-3.0-or-later for the code (LICENSE), CC-BY-4.0 for the releases (data/LICENSE), each named where it is read.

    CI validates CITATION.cff against the Citation File Format schema (``cffconvert --validate``);
    this checks that the licenses it names are the files' and every committed release's.
    """
    assert (ROOT / "LICENSE").read_text().lstrip().startswith("GNU GENERAL PUBLIC LICENSE\n                       Version 3")
    assert (ROOT / "data" / "LICENSE").read_text().startswith("Creative Commons Attribution 4.0 International")
    citation = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    assert citation["license"] == "GPL-3.0-or-later"
    assert [r["license"] for r in citation["references"] if r["type"] == "data"] == [release.DATA_LICENSE]
    assert release.DATA_LICENSE == "CC-BY-4.0"
    unlicensed = [p.name for p in COMMITTED if release.read_manifest(p).get("license") != release.DATA_LICENSE]
    assert unlicensed == []


def test_config_files_merge_as_snakemake_merges_them():
    """A later --configfile's mapping updates the earlier one's key by key; other values are replaced."""
    preset = {"seeds": [1, 2], "accuracy": {"dem_study": False, "subset": "default"}, "campaign": "quick"}
    overlay = {"seeds": [3], "accuracy": {"dem_study": True}}
    assert release.merge_config(preset, overlay) == {"seeds": [3], "campaign": "quick",
                                                     "accuracy": {"dem_study": True, "subset": "default"}}


def gzip_run(tmp_path):
    """A model-made case's pre-shear and Heaviside run as one minimal CSV, gzip-compressed (as in a release)."""
    case = synthetic.write_case(tmp_path / "made", default_params(), seed=1, preshear_strain=2.0,
                                protocols=("heaviside",))
    pre = pd.read_csv(case / "preshear.csv")
    whole = pd.concat([pre, pd.read_csv(case / "heaviside.csv").iloc[1:]], ignore_index=True)
    release.write_csv_gz(whole, tmp_path / "run.csv.gz")
    return pre


def case_yaml(tmp_path, reversal):
    meta = {"pressure": 1.0e5, "inertial_number": 1.0e-3, "cases": [
        {"seed": 1, "runs": [{"file": "run.csv.gz", "protocol": "heaviside", "reversals": [reversal]}]}]}
    return write(meta, tmp_path / "case.yaml")


def test_importer_reads_a_gzip_run_and_takes_the_reversal_row_named_by_its_time(tmp_path):
    """With ``t``, the row at that time starts the reversal, whatever ``strain`` says (here 0.1 short of it)."""
    pre = gzip_run(tmp_path)
    (case,) = import_cases(case_yaml(tmp_path, {"strain": 1.9, "t": float(pre["t"].iloc[-1])}), tmp_path / "dem")
    imported = read_series(case / "preshear.csv")
    assert len(imported) == len(pre) and imported["t"].iloc[-1] == pre["t"].iloc[-1]
    side = yaml.safe_load((case / "heaviside.json").read_text())
    assert side["reversal_strain"] == pytest.approx(2.0)
    (short,) = import_cases(case_yaml(tmp_path, {"strain": 1.9}), tmp_path / "dem-by-strain")
    assert read_series(short / "preshear.csv")["strain"].iloc[-1] == pytest.approx(1.9, abs=0.01)


def test_importer_names_a_reversal_time_with_no_row_and_a_truncated_gzip_file(tmp_path):
    pre = gzip_run(tmp_path)
    with pytest.raises(DEMInputError, match=r"run.csv.gz: reversal 1 at t 1999.5: no data row at that time"):
        import_cases(case_yaml(tmp_path, {"strain": 2.0, "t": float(pre["t"].iloc[-1]) - 0.5}), tmp_path / "dem")
    data = (tmp_path / "run.csv.gz").read_bytes()
    (tmp_path / "run.csv.gz").write_bytes(data[: len(data) // 2])
    with pytest.raises(DEMInputError, match=r"run.csv.gz: not a readable CSV"):
        import_cases(case_yaml(tmp_path, {"strain": 2.0}), tmp_path / "dem")


@pytest.mark.yade
@pytest.mark.slow
@pytest.mark.heavy
def test_release_manifest_names_provenance_and_every_file(released):
    config, results, out = released
    manifest = release.read_manifest(out)
    labels = [f"p100000_I0.01_s{seed}" for seed in SEEDS]
    assert sorted(manifest["cases"]) == labels
    assert manifest["config"] == yaml.safe_load(config.read_text())
    assert manifest["license"] == "CC-BY-4.0"
    assert manifest["yade_version"] == "2023.02a" and len(manifest["code_commit"]) == len(manifest["dem_code_commit"]) == 40
    assert "python -m dem_contract release --cases" in manifest["regenerate"]["release"]
    assert f"results_dir=<results_dir> <results_dir>/dem/{labels[0]}/heaviside.csv" in manifest["regenerate"]["dem"]
    for label in labels:
        for name in ("case.yaml", "heaviside.csv.gz", "sinusoidal.csv.gz", "preshear.final.yade.gz",
                     "sidecars/pack.json", "sidecars/preshear.json", "sidecars/heaviside.json", "sidecars/scene.json"):
            assert f"cases/{label}/{name}" in manifest["files"]
        assert manifest["cases"][label]["cpu_time_s"] > 0 and manifest["cases"][label]["N"] == 56
    assert manifest["total_bytes"] == sum(f["bytes"] for f in manifest["files"].values())
    assert manifest["published"] == {"paper_claims.csv": str(results / "claims" / "paper_claims.csv")}
    assert "published/paper_claims.csv" in manifest["files"]


@pytest.mark.yade
@pytest.mark.slow
@pytest.mark.heavy
def test_release_verifies_and_names_an_edited_or_added_file(released, tmp_path):
    _, _, out = released
    assert release.verify(out) == []
    copy = tmp_path / "tiny"
    shutil.copytree(out, copy)
    case = copy / "cases" / "p100000_I0.01_s2"
    (case / "case.yaml").write_text((case / "case.yaml").read_text().replace("simulator: YADE", "simulator: yade"))
    (copy / "cases" / "notes.txt").write_text("by hand\n")
    problems = release.verify(copy)
    assert any("p100000_I0.01_s2/case.yaml: sha256" in p and "edited after the release" in p for p in problems)
    assert any("notes.txt: not in the manifest" in p for p in problems)
    cli = subprocess.run([sys.executable, "-m", "dem_contract", "verify", str(copy)], cwd=ROOT,
                         capture_output=True, text=True)
    assert cli.returncode == 1 and "2 problem(s)" in cli.stdout


@pytest.mark.yade
@pytest.mark.slow
@pytest.mark.heavy
def test_restored_case_equals_the_dem_it_was_released_from(released, tmp_path):
    """Series value for value (all 17 contract columns), sidecars and scene byte for byte, the state copied."""
    _, results, out = released
    label = "p100000_I0.01_s1"
    restored = release.restore_case(out, label, tmp_path / label)
    original = results / "dem" / label
    for stem in ("preshear", "heaviside", "sinusoidal"):
        pd.testing.assert_frame_equal(pd.read_csv(restored / f"{stem}.csv").astype(float),
                                      pd.read_csv(original / f"{stem}.csv").astype(float), check_exact=True)
    for name in ("scene.json", "pack.json", "preshear.json", "heaviside.json", "sinusoidal.json",
                 "preshear.final.yade.gz"):
        assert filecmp.cmp(restored / name, original / name, shallow=False), name


@pytest.mark.yade
@pytest.mark.slow
@pytest.mark.heavy
def test_release_into_a_non_empty_folder_is_refused(released):
    config, results, out = released
    again = subprocess.run([sys.executable, "-m", "dem_contract", "release", "--cases", str(results / "dem" /
                            "p100000_I0.01_s1"), "--config", str(config), "--out", str(out)], cwd=ROOT,
                           capture_output=True, text=True)
    assert again.returncode == 2 and "exists and is not empty" in again.stderr


@pytest.mark.yade
@pytest.mark.slow
@pytest.mark.heavy
def test_claims_recomputed_from_the_release_alone_are_byte_identical(released, module_workflow_dir, tmp_path):
    """26.4a: no YADE job runs, and paper_claims.csv and power.csv equal the original campaign's byte for byte."""
    _, results, out = released
    fresh = tmp_path / "results"
    config = write(campaign_config(fresh, release=str(out)), tmp_path / "config.yaml")
    run = snakemake("-j1", fresh / "claims" / "paper_claims.csv", "--configfile", config, cwd=module_workflow_dir,
                    timeout=900)
    assert run.returncode == 0, run.stderr[-3000:]
    ran = run.stderr + run.stdout
    assert "rule release_case:" in ran and not any(f"rule {r}:" in ran for r in DEM_RULES)
    for name in ("paper_claims.csv", "power.csv"):
        assert filecmp.cmp(fresh / "claims" / name, results / "claims" / name, shallow=False), name
    assert filecmp.cmp(fresh / "claims" / "paper_claims.csv", out / "published" / "paper_claims.csv", shallow=False)


@pytest.mark.yade
@pytest.mark.slow
@pytest.mark.heavy
def test_adding_a_seed_plans_only_the_new_seeds_dem(released, module_workflow_dir, tmp_path):
    """26.3/26.4b: with seeds 1-3 released and seed 4 added, the dry run's DEM jobs are seed 4's alone."""
    _, _, out = released
    config = write(campaign_config(tmp_path / "results", seeds=[*SEEDS, 4], release=str(out)),
                   tmp_path / "config.yaml")
    run = snakemake("-n", tmp_path / "results" / "claims" / "paper_claims.csv", "--configfile", config,
                    "--quiet", "rules", cwd=module_workflow_dir, timeout=300)
    assert run.returncode == 0, run.stderr[-3000:]
    jobs = planned_jobs(run.stdout)
    assert {rule: jobs.get(rule, 0) for rule in (*DEM_RULES, "release_case")} == {
        "scene": 1, "dem_pack": 1, "dem_preshear": 1, "dem_reversal": 2, "release_case": 3}
    listed = snakemake("-n", tmp_path / "results" / "claims" / "paper_claims.csv", "--configfile", config,
                       cwd=module_workflow_dir, timeout=300)
    dem_jobs = [block for block in listed.stdout.split("\n\n") if any(f"rule {r}:" in block for r in DEM_RULES)]
    assert dem_jobs and all("p100000_I0.01_s4" in block for block in dem_jobs)


@pytest.mark.yade
@pytest.mark.slow
@pytest.mark.skipif(not RUN_RELEASE_DEM, reason="opt-in: RUN_RELEASE_DEM=1 (re-runs a released case's DEM)")
@pytest.mark.heavy
def test_released_case_dem_reruns_identically(released, module_workflow_dir, tmp_path):
    """26.4c: one released case's DEM, re-run from scratch from its manifest's config, equals the release.

    The committed releases' first case (the test-made release when none is committed):
    its series value for value (YADE runs are deterministic here).
    """
    folder = COMMITTED[0] if COMMITTED else released[2]
    manifest = release.read_manifest(folder)
    label, case = next(iter(manifest["cases"].items()))
    config = dict(manifest["config"], results_dir=str(tmp_path / "results"), release=[], allow_outside_tree=True)
    targets = [tmp_path / "results" / case["source"] / label / f"{p}.csv" for p in case["protocols"]]
    run = snakemake("-j1", *targets, "--configfile", write(config, tmp_path / "config.yaml"), cwd=module_workflow_dir,
                    timeout=None)
    assert run.returncode == 0, run.stderr[-3000:]
    restored = release.restore_case(folder, label, tmp_path / "restored")
    for stem in ("preshear", *case["protocols"]):
        pd.testing.assert_frame_equal(pd.read_csv(restored / f"{stem}.csv").astype(float),
                                      pd.read_csv(targets[0].parent / f"{stem}.csv").astype(float),
                                      check_exact=True)


def test_a_missing_release_stops_the_workflow_naming_its_manifest(workflow_dir, tmp_path):
    config = write(campaign_config(tmp_path / "results", release=str(tmp_path / "nothere")), tmp_path / "config.yaml")
    run = snakemake("-n", "--configfile", config, cwd=workflow_dir, timeout=300)
    assert run.returncode == 2
    assert f"config key 'release': {tmp_path / 'nothere' / 'manifest.yaml'}: not readable" in run.stderr


@pytest.mark.parametrize("where, words", [("accuracy/dem/p1", "not a case of a results folder's dem or accuracy/bulk/"),
                                          ("dem/p100000_I0.01_s1", "not a finished DEM case")])
def test_release_of_what_is_not_a_finished_case_is_refused_and_writes_nothing(tmp_path, where, words):
    (tmp_path / "results" / where).mkdir(parents=True)
    run = subprocess.run([sys.executable, "-m", "dem_contract", "release", "--cases", str(tmp_path / "results" / where),
                          "--config", str(ROOT / "config" / "ci.yaml"), "--out", str(tmp_path / "data" / "x")],
                         cwd=ROOT, capture_output=True, text=True)
    assert run.returncode == 2 and words in run.stderr
    assert not (tmp_path / "data" / "x").exists()


PAPER_VALIDATION = ROOT / "data" / "bulk-validation-paper"
RECONCILED_VALIDATION = ROOT / "data" / "bulk-validation-reconciled"
VALIDATIONS = [  # release, overlay of config/bulk.yaml, reference cell, seeds per cell, the quantities the narrow cell fails
    (PAPER_VALIDATION, "config/bulk_validation_paper.yaml", "W4H-H24", 2, ""),
    (RECONCILED_VALIDATION, "config/bulk_validation_reconciled.yaml", "W4H-H37", 4, "Z"),
]


@pytest.mark.slow
@pytest.mark.parametrize("release_dir, overlay, reference, seeds, failing", VALIDATIONS,
                         ids=[v[0].name for v in VALIDATIONS])
def test_the_released_validation_cells_decide_the_narrow_cell_without_yade(workflow_dir, tmp_path, release_dir,
                                                                           overlay, reference, seeds, failing):
    """A bulk-vs-walls overlay with its release: every cell is restored, not run (no DEM rule in the plan), and
    the study's own tolerance rule decides the narrow cell H = 37d, W = 18.5d against the W = 4H wall cell:
    it matches at kappa 1e5, I 1e-3 (H = 24d reference, 2 seeds; docs/findings.md, "The narrow cell at the
    paper's physics"); at the reconciled physics (kappa 700, I 3e-4; the paper's own cell, H = 37d, 4 seeds)
    it matches in mu, |A|, theta_A and phi and fails on Z (docs/findings.md, "The reconciled physics"), the
    tables recomputed equal to the ones the run published, byte for byte."""
    if not release_dir.is_dir():
        pytest.skip(f"{release_dir.name} is not in data/")
    results = tmp_path / "results"
    args = ["bulk_vs_walls", "--configfile", "config/bulk.yaml", overlay,
            "--config", f"results_dir={results}", "allow_outside_tree=True", f"release={release_dir}"]
    plan = dry_run(*args, cwd=workflow_dir)
    assert plan.returncode == 0, plan.stderr[-3000:]
    c = counts(plan.stdout)
    assert c.get("release_bulk_case") == 2 * seeds and not any(
        r.startswith("bulk_study_") and r not in ("bulk_study_cases", "bulk_study_dem") for r in c), c
    run = snakemake("-j1", *args, cwd=workflow_dir, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    table = pd.read_csv(results / "accuracy" / "bulk_vs_walls.csv").set_index("cell")
    assert table.loc[reference, "seeds"] == seeds
    assert bool(table.loc["narrow-H37-W18", "match"]) == (not failing)
    assert str(table.loc["narrow-H37-W18", "failing"]).replace("nan", "") == failing
    for published in sorted((release_dir / "published").glob("*")):
        assert filecmp.cmp(results / "accuracy" / published.name, published, shallow=False), published.name


DECIDE = ROOT / "data" / "bulk-decide"
RUN_RELEASE_CLAIMS = os.environ.get("RUN_RELEASE_CLAIMS") == "1"


#: Presets that recompute a released campaign: (release, the preset's config files in --configfile order).
RELEASED_PRESETS = [
    (DECIDE, ("config/bulk_decide.yaml",)),
    (ROOT / "data" / "bulk-verdict", ("config/bulk_verdict.yaml",)),
    (ROOT / "data" / "bulk-verdict-lammps", ("config/bulk_verdict.yaml", "config/bulk_verdict_lammps.yaml")),
]


@pytest.mark.parametrize("release, configs", RELEASED_PRESETS, ids=[r.name for r, _ in RELEASED_PRESETS])
def test_a_released_campaigns_preset_takes_every_case_from_its_release(workflow_dir, tmp_path, release, configs):
    """Each preset names its release: its dry run restores every case and plans no DEM job (neither engine)."""
    from tests.helpers import counts, dry_run
    assert release.is_dir(), f"{release} is not in data/"
    plan = dry_run("--configfile", *configs, "--config", f"results_dir={tmp_path / 'results'}",
                   "allow_outside_tree=True",
                   cwd=workflow_dir)
    assert plan.returncode == 0, plan.stderr[-3000:]
    c = counts(plan.stdout)
    seeds = yaml.safe_load((ROOT / configs[0]).read_text())["seeds"]
    assert c.get("release_case") == len(seeds) and not any(c.get(r) for r in DEM_RULES), c


@pytest.mark.slow
@pytest.mark.skipif(not (DECIDE.is_dir() and RUN_RELEASE_CLAIMS),
                    reason="opt-in: RUN_RELEASE_CLAIMS=1 (calibrates the deciding campaign from its release, minutes; "
                           ".ci/run runs it)")
def test_the_deciding_campaign_recomputed_from_its_release_gives_its_published_tables(workflow_dir, tmp_path):
    """26.4a on the committed release: calibration, comparison and claims from data/bulk-decide alone (no YADE)
    give every table in its published/ (claims, reversal design, power, plan, parameters): every published row,
    the verdicts and counts exactly, the numbers to dem_contract.published.RTOL (its docstring says why)."""
    from tests.helpers import snakemake as snakemake_in
    results = tmp_path / "results"
    targets = list(published.published_tables(DECIDE, results).values())
    assert {p.name for p in targets} >= {"paper_claims.csv", "params_table.csv"}
    run = snakemake_in("-j2", *targets, "--configfile", "config/bulk_decide.yaml", "--config",
                       f"results_dir={results}", "allow_outside_tree=True", cwd=workflow_dir, timeout=None)
    assert run.returncode == 0, run.stderr[-3000:]
    assert not any(f"rule {r}:" in run.stderr + run.stdout for r in DEM_RULES)
    assert published.compare(DECIDE, results) == []


@pytest.mark.slow
@pytest.mark.skipif(not RUN_RELEASE_CLAIMS, reason="opt-in: RUN_RELEASE_CLAIMS=1 (calibrates a verdict campaign from "
                                                 "its release, about 10 minutes on 2 cores each)")
@pytest.mark.parametrize("release, configs", RELEASED_PRESETS[1:], ids=[r.name for r, _ in RELEASED_PRESETS[1:]])
def test_a_verdict_campaign_recomputed_from_its_release_gives_its_published_tables(workflow_dir, tmp_path, release,
                                                                                  configs):
    """The verdict campaigns (YADE and LAMMPS) from data/ alone, no DEM engine: every published table again."""
    from tests.helpers import snakemake as snakemake_in
    results = tmp_path / "results"
    targets = list(published.published_tables(release, results).values())
    assert {p.name for p in targets} >= {"paper_claims.csv", "params_table.csv"}
    run = snakemake_in("-j2", *targets, "--configfile", *configs, "--config", f"results_dir={results}",
                       "allow_outside_tree=True", cwd=workflow_dir, timeout=None)
    assert run.returncode == 0, run.stderr[-3000:]
    assert not any(f"rule {r}:" in run.stderr + run.stdout for r in DEM_RULES)
    assert published.compare(release, results) == []


def test_a_release_remade_in_place_is_not_called_dirty_for_its_own_deleted_folder(tmp_path):
    """Remaking a committed release deletes its folder first: that deletion is not a change of the code."""
    assert release.excluded_from_status(ROOT / "data" / "x", ROOT) == [":(exclude)data/x"]
    assert release.excluded_from_status(tmp_path / "x", ROOT) == []       # outside the repository: nothing to leave out
