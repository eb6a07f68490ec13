"""The stiffness axis (dem_study/stiffness.py): the per-kappa table and the fabric readings
on a constructed runs table with known means (the per-run summary of a real tiny YADE case:
tests/test_dem_stages.py)."""
import math
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

from dem_contract.published import compare_table
from dem_study import stiffness

ROOT = Path(__file__).resolve().parents[1]


BASE = dict(inertial_number=1e-3, dt_over_tc=0.3, contact_law="viscel", restitution=0.5)


def constructed_runs(checks=()):
    """Two kappas x 3 seeds: kappa 1e5 has |A| higher by 0.02 and X lower by 0.03, with known seed offsets;
    ``checks``: settings at kappa 1e4 off the stiffness axis (dicts of what differs), the same values."""
    rows = []
    settings = [(dict(BASE, kappa=1e4), 0.0, 0.0), (dict(BASE, kappa=1e5), 0.02, -0.03)]
    settings += [(dict(BASE, kappa=1e4, **c), 0.0, 0.0) for c in checks]
    for setting, dA, dX in settings:
        kappa = setting["kappa"]
        for seed, e in zip((1, 2, 3), (-0.001, 0.0, 0.001)):
            rows.append(dict(case=f"s{seed}", **setting, seed=seed, N=626, mu=0.27 + e, A_norm=0.085 + dA + e,
                             X=-0.08 + dX + e, theta_A_deg=137.0 + 10 * e, phi=0.81, Z=2.9 + e, A_min_early=0.01,
                             strain_at_A_min=0.05, mu_early=0.1, core_hours=0.1 * math.sqrt(kappa / 1e4),
                             core_hours_preshear=0.08, X_contract=-0.07 + dX + e, X_no_rattlers=-0.072 + dX + 2 * e))
    return pd.DataFrame(rows)


def test_stiffness_table_gives_seed_means_and_distance_from_the_stiffest_in_standard_errors():
    t = stiffness.stiffness_table(constructed_runs())
    assert list(t["kappa"]) == [1e4, 1e5] and list(t["seeds"]) == [3, 3]
    se = 0.001 / math.sqrt(3)                    # s.d. of (-1, 0, 1) e-3 over sqrt(3)
    assert t["A_norm"].tolist() == pytest.approx([0.085, 0.105])
    assert t["A_norm_se"].tolist() == pytest.approx([se, se])
    assert t["z_A_norm"].iloc[0] == pytest.approx(-0.02 / (math.sqrt(2) * se))
    assert t["z_X"].iloc[0] == pytest.approx(0.03 / (math.sqrt(2) * se))
    assert t["z_A_norm"].iloc[1] == 0
    assert t["core_hours_per_seed"].tolist() == pytest.approx([0.1, 0.1 * math.sqrt(10)])
    assert t["on_axis"].all()


def test_checks_off_the_axis_get_their_own_rows_and_the_axis_its_stiffest_reference():
    """A finer time step and the other restitution law at kappa 1e4 are rows of their own, off the
    axis; the z reference stays the axis's stiffest kappa, not the last row."""
    t = stiffness.stiffness_table(constructed_runs(checks=[dict(dt_over_tc=0.15), dict(contact_law="frictvisco")]))
    assert len(t) == 4 and t["seeds"].tolist() == [3, 3, 3, 3]
    off = t[~t["on_axis"]]
    assert sorted(off["dt_over_tc"]) == [0.15, 0.3] and set(off["kappa"]) == {1e4}
    axis = t[t["on_axis"]].set_index("kappa")
    assert axis.loc[1e5, "z_A_norm"] == 0
    se = 0.001 / math.sqrt(3)
    assert off["z_A_norm"].tolist() == pytest.approx([-0.02 / (math.sqrt(2) * se)] * 2)


def test_fabric_readings_are_paired_by_seed_against_the_contracts():
    r = stiffness.readings_table(constructed_runs()).set_index(["kappa", "reading"])
    assert r.loc[(1e4, "contract"), "minus_contract"] == 0
    # X_no_rattlers - X_contract = -0.002 + e per seed: mean -0.002, s.e. that of e
    assert r.loc[(1e5, "no_rattlers"), "minus_contract"] == pytest.approx(-0.002)
    assert r.loc[(1e5, "no_rattlers"), "minus_contract_se"] == pytest.approx(0.001 / math.sqrt(3))


RELEASES = sorted(p.parent for p in (ROOT / "data").glob("stiffness-*/manifest.yaml"))
DOCUMENTED = ROOT / "docs" / "stiffness"


@pytest.mark.skipif(not RELEASES, reason="no stiffness release under data/")
def test_the_stiffness_study_recomputed_from_its_releases_gives_the_documented_tables(tmp_path):
    """docs/findings.md's stiffness tables (docs/stiffness/, written by the same command) are what the
    released runs give without YADE: every setting's row and every fabric reading, to the last digit."""
    run = subprocess.run([sys.executable, "-m", "dem_study", "stiffness", "--releases", *map(str, RELEASES),
                          "--out", str(tmp_path)], cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    keys = {"stiffness.csv": stiffness.SETTING, "fabric_readings.csv": (*stiffness.SETTING, "reading"),
            "stiffness_runs.csv": (*stiffness.SETTING, "seed")}
    for name, key in keys.items():
        assert compare_table(DOCUMENTED / name, tmp_path / name, keys=key, rtol=1e-9) == [], name
