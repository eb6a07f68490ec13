"""The campaign's summary and the packing's cost run as ``python -m`` command lines, as the rules call them."""
import io
import json
import subprocess
import sys
from pathlib import Path

import pandas as pd

from campaign.summary import summary_table
from dem_contract import synthetic
from model import default_params

ROOT = Path(__file__).resolve().parents[1]
STAGES = ["pack", "preshear", "heaviside", "sinusoidal"]


def model_made_campaign(dem: Path) -> dict:
    """Two model-made cases with the sidecar keys a DEM run writes (and a pack sidecar of its own)."""
    cases = {}
    for seed in (1, 2):
        label = f"p100000_I0.001_s{seed}"
        case = synthetic.write_case(dem / label, default_params(), seed=seed, preshear_strain=2.0)
        (case / "pack.json").write_text(json.dumps({}))
        for k, stage in enumerate(STAGES):
            side = case / f"{stage}.json"
            meta = json.loads(side.read_text())
            meta.update(N=500, kappa_achieved=1e3, inertial_number_achieved=1e-3, dt_over_tc=0.1,
                        steps=1000 * (k + 1), wall_time_s=2.0 * (k + seed), cpu_time_s=1.5 * (k + seed),
                        particle_steps_per_s=5e5)
            side.write_text(json.dumps(meta))
        cases[label] = dict(pressure=1.0e5, inertial_number=1.0e-3, seed=seed)
    return cases


def run(*args, cwd=ROOT):
    return subprocess.run([sys.executable, "-m", *args], cwd=cwd, capture_output=True, text=True, timeout=300)


def test_the_summary_command_writes_the_table_of_its_function_with_the_cases_exactly(tmp_path):
    cases = model_made_campaign(tmp_path / "dem")
    out = tmp_path / "campaign_summary.csv"
    arg = [f"{label}={c['pressure']!r},{c['inertial_number']!r},{c['seed']}" for label, c in cases.items()]
    result = run("campaign.summary", "--dem", str(tmp_path / "dem"), "--cases", *arg,
                 "--stages", "sinusoidal", "heaviside", "preshear", "pack", "--out", str(out))
    assert result.returncode == 0, result.stderr
    table = pd.read_csv(out)
    expected = summary_table(tmp_path / "dem", cases, STAGES)
    assert list(table["case"]) == list(cases)
    assert list(table.columns) == list(expected.columns)
    assert [c for c in table.columns if c.startswith("wall_time_s_")] == [f"wall_time_s_{s}" for s in STAGES]
    pd.testing.assert_frame_equal(table, pd.read_csv(io.StringIO(
        expected.to_csv(index=False, float_format="%.6g"))))


def test_the_summary_command_refuses_a_case_without_its_values_naming_the_format(tmp_path):
    result = run("campaign.summary", "--dem", str(tmp_path), "--cases", "p100000_I0.001_s1",
                 "--stages", "pack", "--out", str(tmp_path / "x.csv"))
    assert result.returncode == 2
    assert "expected LABEL=PRESSURE,I,SEED" in result.stderr


def test_the_packing_cost_command_gives_the_pack_share_of_every_case(tmp_path):
    model_made_campaign(tmp_path / "dem")
    sidecars = sorted(str(p) for p in (tmp_path / "dem").glob("*/*.json") if p.stem in STAGES)
    out = tmp_path / "packing_cost.csv"
    result = run("dem_study.packing_cost", "--campaign", "tiny", "--sidecars", *sidecars, "--out", str(out))
    assert result.returncode == 0, result.stderr
    row = pd.read_csv(out).iloc[0]
    # seed s: pack 1.5 s of 1.5 (s + s+1 + s+2 + s+3) s of CPU; steps 1000 of 10000
    fractions = [s / (4 * s + 6) for s in (1, 2)]
    assert row["n_cases"] == 2 and row["stages"] == "pack+preshear+heaviside+sinusoidal"
    assert abs(row["pack_cpu_fraction_mean"] - sum(fractions) / 2) < 1e-5
    assert abs(row["pack_steps_fraction_max"] - 0.1) < 1e-9 and not row["within_target"]


def test_the_packing_cost_command_names_a_missing_sidecar(tmp_path):
    model_made_campaign(tmp_path / "dem")
    (tmp_path / "dem" / "p100000_I0.001_s2" / "pack.json").write_text(json.dumps({}))
    sidecars = sorted(str(p) for p in (tmp_path / "dem").glob("*/*.json") if p.stem in STAGES)
    result = run("dem_study.packing_cost", "--campaign", "tiny", "--sidecars", *sidecars,
                 "--out", str(tmp_path / "x.csv"))
    assert result.returncode == 1
    assert "p100000_I0.001_s2" in result.stderr and not (tmp_path / "x.csv").exists()
