"""The DEM resolution study in the workflow: planned with accuracy.dem_study on, absent with it off
(Snakemake's dry runs), and the schema stops a bad study value before any job (the pre-flight command
the Snakefile's gate runs, ``helpers.preflight_check``)."""
import shutil

import pandas as pd
import pytest
import yaml

from tests.helpers import ROOT, counts, preflight_check, snakemake


def test_paper_preset_plans_the_study_once_per_point(shared_dry_run):
    from dem_study import grid
    config = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    assert config["accuracy"]["dem_study"] is True
    n = len(grid.unique_points(grid.expand(config["accuracy"])))
    result = shared_dry_run("--configfile", "config/config.yaml")
    assert result.returncode == 0, result.stderr[-3000:]
    c = counts(result.stdout)
    assert c["dem_study"] == 1
    for rule in ["dem_study_scene", "dem_study_pack", "dem_study_preshear", "dem_study_heaviside"]:
        assert c[rule] == n, rule


@pytest.mark.parametrize("preset", ["quick", "ci"])
def test_small_presets_do_not_plan_the_study(preset, shared_dry_run):
    config = yaml.safe_load((ROOT / "config" / f"{preset}.yaml").read_text())
    assert not config.get("accuracy", {}).get("dem_study", False)
    result = shared_dry_run("--configfile", f"config/{preset}.yaml")
    assert result.returncode == 0, result.stderr[-3000:]
    assert not any(rule.startswith("dem_study") for rule in counts(result.stdout))


def test_bad_study_value_stops_before_any_job(tmp_path):
    config = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    config["accuracy"]["dem_grid"]["dt_over_tc"] = [0.5, 0.1]
    path = tmp_path / "config.yaml"
    path.write_text(yaml.safe_dump(config))
    result = preflight_check(path)
    message = result.stderr
    assert result.returncode != 0
    assert "dt_over_tc" in message and "maximum of 0.3" in message, message[-2000:]


@pytest.mark.yade
@pytest.mark.slow
@pytest.mark.skipif(shutil.which("yade") is None, reason="needs YADE (Debian package yade)")
@pytest.mark.heavy
def test_tiny_study_runs_end_to_end_through_snakemake(tmp_path, workflow_dir):
    """Three real ~200-disk points (two seeds at the base, one other I): about a minute on one core."""
    config = yaml.safe_load((ROOT / "config" / "ci.yaml").read_text())
    config["results_dir"] = str(tmp_path / "results")
    config["allow_outside_tree"] = True  # a results folder under pytest's tmp_path
    config["accuracy"] = dict(
        ode_work_precision=False, dem_study=True, subset="default",
        base=dict(kappa=1e3, inertial_number=1e-2, H_over_d=8, dt_over_tc=0.1, fine_interval=0.002,
                  coarse_interval=0.01),
        dem_grid=dict(inertial_number=[1e-2, 3e-2], dt_over_tc=[0.1, 0.3]),
        default_subset=dict(inertial_number=[3e-2]),
        seeds=[1, 2], preshear_strain=0.6, heaviside_strain=0.2, steady_window=0.2,
    )
    path = tmp_path / "config.yaml"
    path.write_text(yaml.safe_dump(config))
    target = f"{config['results_dir']}/accuracy/dem_cost.csv"
    result = snakemake("-j1", target, "--configfile", path, cwd=workflow_dir, timeout=900)
    assert result.returncode == 0, result.stderr[-3000:]
    cost = pd.read_csv(target)
    assert set(cost["axis"]) == {"inertial_number", "seed"}
    assert (cost["particle_steps_per_s"] > 1e5).all() and (cost["wall_time_s"] > 0).all()
    base = cost[(cost["axis"] == "inertial_number") & cost["finest"]].iloc[0]
    assert base["d_mu"] == 0 and base["d_transient_mu"] == 0
    assert 0.1 < base["mu_steady"] < 0.6 and 0 < base["A_norm_steady"] < 0.5
    assert 90 < base["theta_A_deg_steady"] < 180          # compressive diagonal (docs/model.md)
    assert cost["seed_spread_mu"].iloc[0] > 0
    mu = pd.read_csv(f"{config['results_dir']}/accuracy/mu_of_I.csv")
    assert (mu["kind"] == "campaign").sum() == 1 and 0.1 < mu["mu_c"].iloc[0] < 0.6
