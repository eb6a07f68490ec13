"""The bulk-vs-walls study in the workflow: one DEM case per (cell, seed) through the campaign's
rules, nothing of it with the study off, and a bad cell stopped before any job, naming the key."""
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from dem_study import bulk_cells
from tests import helpers
from tests.helpers import ROOT, counts, snakemake
QUICK = yaml.safe_load((ROOT / "config" / "quick.yaml").read_text())


def two_cells(tmp_path):
    config = yaml.safe_load((ROOT / "config" / "quick.yaml").read_text())
    config["results_dir"] = str(tmp_path / "results")
    config["allow_outside_tree"] = True  # a results folder under pytest's tmp_path
    config["accuracy"]["bulk_vs_walls"] = dict(
        run=True,
        cells={"W4H-H12": dict(kind="walls", H_over_d=12, W_over_H=4),
               "periodic-N500": dict(kind="periodic", H_over_d=23, W_over_H=1)},
        references=["W4H-H12"], tall_reference="W4H-H12", seeds=[1],
        kappa=1.0e3, inertial_number=5.0e-3, preshear_strain=1.5, heaviside_strain=0.3, steady_window=1.0)
    return config


def dry_run(config, tmp_path, *targets):
    """Snakemake's dry run of ``targets`` on ``config``, in a working copy of its own under ``tmp_path``."""
    path = tmp_path / "config.yaml"
    path.write_text(yaml.safe_dump(config))
    return helpers.dry_run(*targets, "--configfile", path, cwd=helpers.workflow_copy(tmp_path / "workflow"))


def test_two_cells_one_seed_plan_one_dem_case_per_cell(tmp_path):
    result = dry_run(two_cells(tmp_path), tmp_path, "bulk_study_dem")
    assert result.returncode == 0, result.stderr[-3000:]
    c = counts(result.stdout)
    for rule in ["bulk_study_scene", "bulk_study_pack", "bulk_study_preshear", "bulk_study_heaviside"]:
        assert c.get(rule) == 2, (rule, c)
    assert c.get("bulk_study_cases") == 1
    assert not any(rule.startswith("dem_") for rule in c), c   # the campaign is not run


def test_the_default_target_plans_the_study_and_its_analysis_when_it_is_on(tmp_path):
    result = dry_run(two_cells(tmp_path), tmp_path)
    assert result.returncode == 0, result.stderr[-3000:]
    c = counts(result.stdout)
    assert c.get("bulk_study_heaviside") == 2 and c.get("bulk_vs_walls") == 1 and c.get("bulk_study_dem") == 1


def test_the_analysis_target_plans_the_dem_cases_and_no_campaign(tmp_path):
    result = dry_run(two_cells(tmp_path), tmp_path, "bulk_vs_walls")
    assert result.returncode == 0, result.stderr[-3000:]
    c = counts(result.stdout)
    assert c.get("bulk_vs_walls") == 1 and c.get("bulk_study_pack") == 2
    assert not any(rule.startswith("dem_") or rule.startswith("calibrat") for rule in c), c


def test_the_shipped_overlay_plans_every_cell_and_seed_and_nothing_of_the_campaign(workflow_dir):
    """config/bulk_validation.yaml over config/quick.yaml, as its header says to run it."""
    overlay = yaml.safe_load((ROOT / "config" / "bulk_validation.yaml").read_text())["accuracy"]["bulk_vs_walls"]
    seeds = {name: len(spec.get("seeds", overlay["seeds"])) for name, spec in overlay["cells"].items()}
    n = sum(seeds.values())
    n_train = sum(k for name, k in seeds.items() if "train" in overlay["cells"][name])
    result = helpers.dry_run("bulk_vs_walls", "--configfile", "config/quick.yaml", "config/bulk_validation.yaml",
                             cwd=workflow_dir)
    assert result.returncode == 0, result.stderr[-3000:]
    c = counts(result.stdout)
    assert c.get("bulk_study_heaviside") == n - n_train and c.get("bulk_study_train") == n_train > 0
    assert c.get("bulk_study_pack") == n and c.get("bulk_vs_walls") == 1
    assert not any(rule.startswith("dem_") for rule in c), c


@pytest.mark.parametrize("overlay, kappa, inertial_number, seeds", [
    ("bulk_validation_reconciled.yaml", 7.0e2, 3.0e-4, 4),   # the bulk preset's own physics
    ("bulk_validation_paper.yaml", 1.0e5, 1.0e-3, 2),        # the earlier reading, its guards as it ran
])
def test_a_validation_overlay_plans_the_wide_and_the_narrow_cell_at_its_physics(workflow_dir, overlay, kappa,
                                                                              inertial_number, seeds):
    """A bulk-vs-walls overlay over config/bulk.yaml: 2 cells x its seeds, pre-shear and one Heaviside reversal
    each, at the overlay's kappa and I (the reconciled one the bulk preset's own), and nothing of the bulk campaign."""
    study = yaml.safe_load((ROOT / "config" / overlay).read_text())["accuracy"]["bulk_vs_walls"]
    bulk = yaml.safe_load((ROOT / "config" / "bulk.yaml").read_text())
    assert (study["kappa"], study["inertial_number"], len(study["seeds"])) == (kappa, inertial_number, seeds)
    reconciled = yaml.safe_load((ROOT / "config" / "bulk_validation_reconciled.yaml").read_text())
    assert (bulk["material"]["kappa"], bulk["loading"]["inertial_numbers"]) == (
        reconciled["accuracy"]["bulk_vs_walls"]["kappa"], [reconciled["accuracy"]["bulk_vs_walls"]["inertial_number"]])
    result = helpers.dry_run("bulk_vs_walls", "--configfile", "config/bulk.yaml", f"config/{overlay}",
                             cwd=workflow_dir)
    assert result.returncode == 0, result.stderr[-3000:]
    c = counts(result.stdout)
    assert c.get("bulk_study_pack") == c.get("bulk_study_heaviside") == 2 * seeds and c.get("bulk_vs_walls") == 1
    assert not any(rule.startswith("dem_") for rule in c), c


def test_a_train_cell_runs_its_train_with_its_own_seeds_in_place_of_the_heaviside_reversal(tmp_path):
    config = two_cells(tmp_path)
    config["accuracy"]["bulk_vs_walls"]["cells"]["periodic-N500"].update(train={"every": 0.3, "reversals": 4},
                                                                         seeds=[7, 8])
    result = dry_run(config, tmp_path, "bulk_study_dem")
    assert result.returncode == 0, result.stderr[-3000:]
    c = counts(result.stdout)
    assert c.get("bulk_study_train") == 2 and c.get("bulk_study_heaviside") == 1 and c.get("bulk_study_pack") == 3
    scene = bulk_cells.case_scene(config, "periodic-N500_s7")
    assert scene["schedules"] == {"train": {"train": {"every": 0.3, "reversals": 4, "transition": "heaviside"}}}


def test_a_train_shorter_than_the_compared_transient_is_stopped_naming_its_key(tmp_path):
    """The study's own check, which bulk_study.smk stops on before any job (that wiring: the wide cell's test)."""
    config = two_cells(tmp_path)
    config["accuracy"]["bulk_vs_walls"]["cells"]["periodic-N500"]["train"] = {"every": 0.2, "reversals": 4}
    problems = bulk_cells.problems(config)
    assert any("accuracy.bulk_vs_walls.cells.periodic-N500.train.every = 0.2" in p for p in problems), problems


def test_study_off_plans_none_of_it(tmp_path):
    config = two_cells(tmp_path)
    config["accuracy"]["bulk_vs_walls"]["run"] = False
    result = dry_run(config, tmp_path)
    assert result.returncode == 0, result.stderr[-3000:]
    assert not any(rule.startswith("bulk_study") for rule in counts(result.stdout))


def test_a_wide_periodic_cell_is_stopped_naming_its_key(tmp_path):
    """Through Snakemake: bulk_study.smk stops on the study's check with exit 2 before any job."""
    config = two_cells(tmp_path)
    config["accuracy"]["bulk_vs_walls"]["cells"]["periodic-N500"]["W_over_H"] = 2
    result = dry_run(config, tmp_path, "bulk_study_dem")
    assert result.returncode == 2, result.stderr[-3000:]
    assert "accuracy.bulk_vs_walls.cells.periodic-N500.W_over_H" in result.stderr, result.stderr[-3000:]
    assert "Traceback" not in result.stderr


def test_a_reference_that_is_not_a_cell_is_stopped_naming_the_key(tmp_path):
    """The study's own check, which bulk_study.smk stops on before any job (that wiring: the wide cell's test)."""
    config = two_cells(tmp_path)
    config["accuracy"]["bulk_vs_walls"]["references"] = ["W4H-H12", "W4H-H37"]
    problems = bulk_cells.problems(config)
    assert any("accuracy.bulk_vs_walls.references: 'W4H-H37' is not a cell" in p for p in problems), problems


def test_case_scene_changes_only_the_cell_kappa_rate_and_strains():
    config = two_cells(Path("/tmp"))
    config["material"]["kappa"] = 1.0e5
    scene = bulk_cells.case_scene(config, "periodic-N500_s1")
    assert scene["cell"] == {"kind": "periodic"} and scene["geometry"] == {"H_over_d": 23, "W_over_H": 1}
    assert scene["material"]["kappa"] == 1.0e3 and scene["loading"]["inertial_number"] == 5.0e-3
    assert scene["preshear"] == {"strain": 1.5} and scene["heaviside"] == {"strain": 0.3}
    assert "sinusoidal" not in scene and "bulk_exclusion_d" not in scene["sampling"]
    walls = bulk_cells.case_scene(config, "W4H-H12_s1")
    assert "cell" not in walls and walls["sampling"]["bulk_exclusion_d"] == QUICK["sampling"]["bulk_exclusion_d"]
    assert walls["timestep"] == QUICK["timestep"] and walls["seed"] == 1


def test_disk_counts_follow_the_scene_for_both_cell_kinds():
    assert bulk_cells.n_disks("walls", 12, 4) == 496          # the quick cell (its sidecars: N = 496)
    assert bulk_cells.n_disks("periodic", 23, 1) == 497       # 0.94 H W: the whole cell holds grains


def test_estimate_grows_with_disks_and_lists_every_case(tmp_path):
    est = bulk_cells.estimate(two_cells(tmp_path))
    assert list(est["case"]) == ["W4H-H12_s1", "periodic-N500_s1"]
    assert (est["est_core_s"] > 0).all()
    assert est["est_core_s"].iloc[0] == pytest.approx(est["est_core_s"].iloc[1], rel=0.01)  # 496 and 497 disks


@pytest.mark.yade
@pytest.mark.slow
@pytest.mark.skipif(shutil.which("yade") is None, reason="needs YADE (Debian package yade)")
@pytest.mark.heavy
def test_tiny_study_runs_end_to_end_through_snakemake(tmp_path, workflow_dir):
    """Two real ~100-disk cells (walls and periodic) x two seeds, to the table and the figure."""
    config = yaml.safe_load((ROOT / "config" / "ci.yaml").read_text())
    config["results_dir"] = str(tmp_path / "results")
    config["allow_outside_tree"] = True  # a results folder under pytest's tmp_path
    config["accuracy"] = dict(ode_work_precision=False, bulk_vs_walls=dict(
        run=True,
        cells={"walls-H8": dict(kind="walls", H_over_d=8, W_over_H=2),
               "periodic-H10": dict(kind="periodic", H_over_d=10, W_over_H=1),
               "walls-H8-train": dict(kind="walls", H_over_d=8, W_over_H=2, seeds=[3],
                                      train={"every": 0.2, "reversals": 2})},
        references=["walls-H8"], tall_reference="walls-H8", seeds=[1, 2],
        kappa=1.0e3, inertial_number=1.0e-2, pack={"ke_max": 1.0e-4},
        preshear_strain=0.6, heaviside_strain=0.2, steady_window=0.3, early_strain=0.1))
    path = tmp_path / "config.yaml"
    path.write_text(yaml.safe_dump(config))
    result = snakemake("-j1", "bulk_vs_walls", "--configfile", path, cwd=workflow_dir, timeout=900)
    assert result.returncode == 0, result.stderr[-3000:]
    out = Path(config["results_dir"]) / "accuracy"
    table = pd.read_csv(out / "bulk_vs_walls.csv")
    row = table[table["cell"] == "periodic-H10"].iloc[0]
    assert row["reference"] == "walls-H8" and row["N"] == bulk_cells.n_disks("periodic", 10, 1)
    assert 0.1 < row["mu"] < 0.6 and 0 < row["A_norm"] < 0.5 and 90 < row["theta_A_deg"] < 180
    assert 0.7 < row["phi"] < 0.9 and 2.5 < row["Z"] < 5 and row["mu_se"] > 0
    assert row["core_hours_per_seed"] > 0 and np.isfinite(row["info_ratio_A_norm"])
    assert (out / "bulk_vs_walls.png").stat().st_size > 10_000
    cost = pd.read_csv(out / "bulk_cost.csv")
    assert len(cost) == 5 and (cost["cpu_time_s"] > 0).all()
    train = table[table["cell"] == "walls-H8-train"].iloc[0]
    assert train["transients"] == 2 and train["seeds"] == 1 and 0 < train["A_norm"] < 0.5


def test_a_narrow_cell_below_the_scene_range_is_named_by_the_preflight(tmp_path):
    import preflight
    config = two_cells(tmp_path)
    config["accuracy"]["bulk_vs_walls"]["cells"]["narrow-H37-W16"] = dict(kind="walls", H_over_d=37, W_over_H=16 / 37)
    lines = preflight.check(config)
    assert any("accuracy.bulk_vs_walls.cells.narrow-H37-W16.W_over_H" in line and "minimum of 0.5" in line
               for line in lines), lines


def test_estimate_prints_the_cost_per_cell_of_the_shipped_overlay(capsys):
    from dem_study.bulk_cli import main
    assert main(["estimate", "--configfile", str(ROOT / "config" / "quick.yaml"),
                 str(ROOT / "config" / "bulk_validation.yaml")]) == 0
    out = capsys.readouterr().out
    overlay = yaml.safe_load((ROOT / "config" / "bulk_validation.yaml").read_text())["accuracy"]["bulk_vs_walls"]
    assert all(cell in out for cell in overlay["cells"])
    n = sum(len(spec.get("seeds", overlay["seeds"])) for spec in overlay["cells"].values())
    assert f"{n} DEM cases" in out and "core-hours" in out


def test_estimate_without_the_block_exits_2_naming_it(capsys):
    from dem_study.bulk_cli import main
    assert main(["estimate", "--configfile", str(ROOT / "config" / "ci.yaml")]) == 2
    assert "accuracy.bulk_vs_walls" in capsys.readouterr().err
