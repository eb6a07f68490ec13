"""The DEM resolution study in the workflow: planned with accuracy.dem_study on, absent with it off,
and the schema stops a bad study value before any job."""
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]


def dry_run(*args):
    return subprocess.run([sys.executable, "-m", "snakemake", "-n", "--quiet", "rules", *args],
                          cwd=ROOT, capture_output=True, text=True, timeout=300)


def counts(stdout):
    out = {}
    for line in stdout.splitlines():
        parts = line.split()
        if len(parts) == 2 and parts[1].isdigit():
            out[parts[0]] = int(parts[1])
    return out


def test_paper_preset_plans_the_study_once_per_point():
    from dem_study import grid
    config = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    assert config["accuracy"]["dem_study"] is True
    n = len(grid.unique_points(grid.expand(config["accuracy"])))
    result = dry_run("--configfile", "config/config.yaml", "--forceall")
    assert result.returncode == 0, result.stderr[-3000:]
    c = counts(result.stdout)
    assert c["dem_study"] == 1
    for rule in ["dem_study_scene", "dem_study_pack", "dem_study_preshear", "dem_study_heaviside"]:
        assert c[rule] == n, rule


@pytest.mark.parametrize("preset", ["quick", "ci"])
def test_small_presets_do_not_plan_the_study(preset):
    config = yaml.safe_load((ROOT / "config" / f"{preset}.yaml").read_text())
    assert not config.get("accuracy", {}).get("dem_study", False)
    result = dry_run("--configfile", f"config/{preset}.yaml", "--forceall")
    assert result.returncode == 0, result.stderr[-3000:]
    assert not any(rule.startswith("dem_study") for rule in counts(result.stdout))


def test_bad_study_value_stops_before_any_job(tmp_path):
    config = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    config["accuracy"]["dem_grid"]["dt_over_tc"] = [0.5, 0.1]
    path = tmp_path / "config.yaml"
    path.write_text(yaml.safe_dump(config))
    result = dry_run("--configfile", str(path))
    message = result.stdout + result.stderr
    assert result.returncode != 0
    assert "dt_over_tc" in message and "maximum of 0.3" in message, message[-2000:]
