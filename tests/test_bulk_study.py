"""The bulk-vs-walls analysis (dem_study/bulk.py) on constructed series with known seed means,
seed spreads, offsets and CPU costs: means and standard errors, the match against a reference,
the information per core-hour and its ratio, and the command line's outputs and errors."""
import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from dem_study import bulk, bulk_cost
from dem_study.analysis import StudyInputError, strain_edges
from dem_study.bulk_cli import main

MU, A0, THETA, PHI, Z = 0.29, 0.095, 133.0, 0.82, 3.6
SEEDS = (1, 2, 3)
SPREAD = np.array([-1.0, 0.0, 1.0])   # per-seed offsets in units of a cell's spread: SE = spread / sqrt(3)


def A_components(norm, theta_deg):
    t = np.radians(2 * np.asarray(theta_deg))
    r = np.asarray(norm) / np.sqrt(2)
    return r * np.cos(t), r * np.sin(t)


def transient(x):
    """A made-up Heaviside transient: mu dips and recovers, |A| collapses and recovers, theta turns."""
    return MU * (1 - 0.8 * np.exp(-x / 0.03)), A0 * (1 - 0.9 * np.exp(-x / 0.04)), 50 + 83 * np.exp(-x / 0.05)


def write_case(d: Path, N=500, dtheta=0.0, dA=0.0, ttheta=0.0, tA=0.0, cpu_s=(20.0, 30.0, 10.0),
               preshear_strain=1.5, heaviside_strain=0.3, fine=0.001):
    """A case folder: a steady pre-shear at (MU, A0 + dA, THETA + dtheta, PHI, Z) and a Heaviside
    transient shifted by (tA, ttheta); sidecars with the given CPU seconds of pack, preshear, heaviside."""
    d.mkdir(parents=True, exist_ok=True)
    s = np.arange(0, preshear_strain + 1e-12, 0.005)
    a, b = A_components(A0 + dA, THETA + dtheta)
    cols = dict(t=s / 5e-3, strain=s, gammadot=5e-3, mu=MU, A_xx=a, A_xy=b, phi=PHI, Z=Z)
    pd.DataFrame({k: np.broadcast_to(v, s.shape) for k, v in cols.items()}).to_csv(d / "preshear.csv", index=False)
    x = np.arange(fine, heaviside_strain + 1e-12, fine)
    mu, norm, theta = transient(x)
    a, b = A_components(norm + tA, theta + ttheta)
    pd.DataFrame(dict(t=(preshear_strain + x) / 5e-3, strain=preshear_strain - x, gammadot=-5e-3, mu=mu, A_xx=a,
                      A_xy=b)).to_csv(d / "heaviside.csv", index=False)
    for stage, cpu in zip(bulk_cost.STAGES, cpu_s):
        side = dict(N=N, cpu_time_s=cpu, wall_time_s=1.5 * cpu, strain_start=preshear_strain * (stage != "pack"))
        if stage == "heaviside":
            side["reversal_strain"], side["reversal_t"] = preshear_strain, preshear_strain / 5e-3
        (d / f"{stage}.json").write_text(json.dumps(side))


# cell -> (kind, N, steady theta offset, theta spread, |A| spread of the transient, CPU seconds per seed)
CELLS = {
    "W4H-H37": ("walls", 5000, 0.0, 1.0, 0.010, (600.0, 900.0, 300.0)),
    "W4H-H24": ("walls", 2000, 0.0, 1.0, 0.010, (200.0, 300.0, 100.0)),
    "periodic-N500": ("periodic", 500, 0.0, 1.0, 0.005, (60.0, 90.0, 30.0)),   # half the spread, 1/10 the cost
    "narrow-H37-W18": ("walls", 600, 6.0, 1.0, 0.010, (60.0, 90.0, 30.0)),     # theta 6 deg off
}
REFS = ["W4H-H24", "W4H-H37"]


def cases_table():
    rows = [dict(case=f"{cell}_s{seed}", cell=cell, seed=seed, kind=kind, H_over_d=37.0, W_over_d=148.0)
            for cell, (kind, *_) in CELLS.items() for seed in SEEDS]
    return pd.DataFrame(rows)


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    root = tmp_path_factory.mktemp("bulk")
    for cell, (kind, N, dtheta, theta_spread, a_spread, cpu) in CELLS.items():
        for seed, k in zip(SEEDS, SPREAD):
            write_case(root / f"{cell}_s{seed}", N=N, dtheta=dtheta + k * theta_spread,
                       ttheta=dtheta + k * theta_spread, tA=k * a_spread, cpu_s=cpu)
    cases = cases_table()
    cases.to_csv(root / "cases.csv", index=False)
    table, cells, curves = bulk.analyse(cases, root, 1.0, strain_edges(0.3, 0.01), 0.1, REFS, "W4H-H37")
    return root, table, cells.set_index("cell"), curves


def test_steady_values_are_seed_means_with_their_standard_error(study):
    _, _, cells, _ = study
    ref = cells.loc["W4H-H37"]
    assert ref["mu"] == pytest.approx(MU) and ref["phi"] == pytest.approx(PHI) and ref["Z"] == pytest.approx(Z)
    assert ref["theta_A_deg"] == pytest.approx(THETA, abs=1e-6)
    assert ref["theta_A_deg_se"] == pytest.approx(1 / math.sqrt(3), rel=1e-6)   # offsets -1, 0, 1 degree
    assert ref["mu_se"] == pytest.approx(0, abs=1e-12)
    assert ref["N"] == 5000 and ref["seeds"] == 3
    assert ref["core_hours_per_seed"] == pytest.approx(1800 / 3600)
    assert ref["core_hours"] == pytest.approx(3 * 1800 / 3600)
    assert ref["core_hours_reversal_per_seed"] == pytest.approx(300 / 3600)


def test_a_cell_like_the_reference_matches_and_an_offset_one_is_named(study):
    _, table, _, _ = study
    rows = table.set_index(["cell", "reference"])
    same = rows.loc[("periodic-N500", "W4H-H37")]
    assert bool(same["match"]) and same["failing"] == ""
    off = rows.loc[("narrow-H37-W18", "W4H-H37")]
    assert not bool(off["match"])
    assert off["failing"] == "theta_A_deg, transient_theta_A_deg"
    assert off["d_theta_A_deg"] == pytest.approx(6.0, abs=1e-6)
    assert off["z_theta_A_deg"] == pytest.approx(6.0 / math.sqrt(2 / 3), rel=1e-6)
    assert off["transient_theta_A_deg_rms"] == pytest.approx(6.0, abs=0.05)


def test_every_cell_is_set_against_every_other_reference(study):
    _, table, _, _ = study
    pairs = set(zip(table["cell"], table["reference"]))
    assert ("W4H-H24", "W4H-H37") in pairs and ("W4H-H37", "W4H-H24") in pairs
    assert not any(c == r for c, r in pairs)
    assert len(table) == 2 * (len(CELLS) - 2) + 2


def test_information_per_core_hour_follows_spread_and_cost(study):
    _, table, cells, _ = study
    per_cell = table.drop_duplicates("cell").set_index("cell")
    # the tall cell: |A| spread 0.01 -> early SE 0.01/sqrt(3), 1.5 core-hours (|A| of the bin-mean
    # fabric: within 1 % of the per-sample shift while theta turns inside a bin)
    assert cells.loc["W4H-H37", "early_se_A_norm"] == pytest.approx(0.01 / math.sqrt(3), rel=0.01)
    assert cells.loc["W4H-H37", "info_A_norm"] == pytest.approx(
        1 / (cells.loc["W4H-H37", "early_se_A_norm"] ** 2 * 1.5), rel=1e-9)
    # half the spread at a tenth of the cost: 4 x 10 = 40 times the information per core-hour
    assert per_cell.loc["periodic-N500", "info_ratio_A_norm"] == pytest.approx(40, rel=0.02)
    assert per_cell.loc["W4H-H37", "info_ratio_A_norm"] == pytest.approx(1)
    # and the tall cell's SE for 1/40 of its 1.5 core-hours
    assert per_cell.loc["periodic-N500", "core_hours_to_tall_se_A_norm"] == pytest.approx(1.5 / 40, rel=0.02)
    assert per_cell.loc["W4H-H37", "core_hours_to_tall_se_theta_A_deg"] == pytest.approx(1.5, rel=1e-3)


def test_verdict_names_the_matching_cells_and_the_best_by_its_weaker_information_ratio(study):
    _, table, _, _ = study
    v = bulk.verdict(table, REFS, "W4H-H37")
    assert v["matching_every_reference"] == ["periodic-N500"]          # the narrow cell's theta is 6 deg off
    assert v["best"] == "periodic-N500"
    # theta_A: the same spread at a tenth of the cost (10x), |A|: 40x; the weaker of the two counts
    theta_ratio = table.set_index("cell").loc["periodic-N500", "info_ratio_theta_A_deg"].iloc[0]
    assert v["best_info_ratio"] == pytest.approx(min(theta_ratio, 40), rel=1e-9)
    assert v["best_info_ratio"] > 10 and v["best_reaches_target"]
    assert v["cells"]["narrow-H37-W18"]["failing"]["W4H-H37"] == "theta_A_deg, transient_theta_A_deg"


def test_one_seed_has_no_standard_error_and_does_not_match(tmp_path):
    for cell in ("W4H-H37", "periodic-N500"):
        write_case(tmp_path / f"{cell}_s1")
    cases = cases_table().query("seed == 1 and cell in ['W4H-H37', 'periodic-N500']")
    table, _, _ = bulk.analyse(cases, tmp_path, 1.0, strain_edges(0.3, 0.01), 0.1, ["W4H-H37"], "W4H-H37")
    row = table.set_index("cell").loc["periodic-N500"]
    assert not bool(row["match"]) and "mu (no SE)" in row["failing"]


def test_command_line_writes_the_table_and_the_figure(study, tmp_path):
    root, *_ = study
    out = tmp_path / "bulk_vs_walls.csv"
    fig = tmp_path / "bulk_vs_walls.png"
    rc = main(["analyse", "--cases", str(root / "cases.csv"), "--bulk-dir", str(root), "--out-table", str(out),
               "--out-figure", str(fig), "--out-summary", str(tmp_path / "s.json"), "--references", *REFS,
               "--tall-reference", "W4H-H37", "--heaviside-strain", "0.3"])
    assert rc == 0
    table = pd.read_csv(out)
    assert {"match", "failing", "info_ratio_theta_A_deg", "transient_mu_rms", "phi_se"} <= set(table.columns)
    assert fig.stat().st_size > 10_000
    assert json.loads((tmp_path / "s.json").read_text())["best"] == "periodic-N500"


def test_a_missing_case_is_named_with_exit_code_2(study, tmp_path, capsys):
    root, *_ = study
    cases = pd.read_csv(root / "cases.csv")
    cases.loc[len(cases)] = dict(case="periodic-N2000_s1", cell="periodic-N2000", seed=1, kind="periodic",
                                 H_over_d=46.0, W_over_d=46.0)
    cases.to_csv(tmp_path / "cases.csv", index=False)
    rc = main(["analyse", "--cases", str(tmp_path / "cases.csv"), "--bulk-dir", str(root),
               "--out-table", str(tmp_path / "t.csv"), "--out-figure", str(tmp_path / "f.png"),
               "--references", *REFS, "--heaviside-strain", "0.3"])
    assert rc == 2
    err = capsys.readouterr().err
    assert "periodic-N2000_s1" in err and "pack.json" in err and "Traceback" not in err


def test_a_reference_without_runs_is_named(study):
    root, *_ = study
    with pytest.raises(StudyInputError, match="W4H-H12"):
        bulk.analyse(cases_table(), root, 1.0, strain_edges(0.3, 0.01), 0.1, ["W4H-H12"], None)


def write_train_case(d: Path, reversals: int, every=0.3, preshear_strain=1.5, fine=0.001, mirror=True,
                     cpu_s=(60.0, 90.0, 300.0)):
    """A case whose reversal run is a train: ``reversals`` reversals ``every`` strain apart, each
    followed by ``transient``; a reversal back along the pre-shear (every second one) is its mirror
    image (A_xy -> -A_xy), or, with ``mirror=False``, wrongly the same fabric."""
    write_case(d, N=600, cpu_s=cpu_s[:2] + (0.0,), preshear_strain=preshear_strain)
    (d / "heaviside.csv").unlink(), (d / "heaviside.json").unlink()
    rows, marks = [], []
    x = np.arange(fine, every + 1e-12, fine)
    mu, norm, theta = transient(x)
    a, b = A_components(norm, theta)
    s0 = preshear_strain
    for k in range(reversals):
        sign = -1.0 if k % 2 == 0 else 1.0            # against the pre-shear, then back
        t0 = (preshear_strain + k * every) / 5e-3
        marks.append(dict(t=t0, strain=s0))
        rows.append(pd.DataFrame(dict(t=t0 + x / 5e-3, strain=s0 + sign * x, gammadot=sign * 5e-3, mu=mu,
                                      A_xx=a, A_xy=-sign * b if mirror else b)))
        s0 += sign * every
    pd.concat(rows).to_csv(d / "train.csv", index=False)
    (d / "train.json").write_text(json.dumps(dict(N=600, cpu_time_s=cpu_s[2], wall_time_s=cpu_s[2],
                                                  strain_start=preshear_strain, reversals=marks)))


def train_study(root: Path, mirror=True):
    for seed in SEEDS:
        write_train_case(root / f"train_s{seed}", reversals=4, mirror=mirror)
        write_case(root / f"ref_s{seed}", N=5000, cpu_s=(600.0, 900.0, 300.0),
                   dtheta=float(SPREAD[seed - 1]), ttheta=float(SPREAD[seed - 1]), tA=0.01 * SPREAD[seed - 1])
    cases = pd.DataFrame([dict(case=f"{c}_s{s}", cell=c, seed=s, kind="walls", H_over_d=37.0, W_over_d=18.5,
                               stage=st) for c, st in (("ref", "heaviside"), ("train", "train")) for s in SEEDS])
    return bulk.analyse(cases, root, 1.0, strain_edges(0.3, 0.01), 0.1, ["ref"], "ref")


def test_a_train_gives_one_transient_per_reversal_each_mirrored_into_the_first_reversals_frame(tmp_path):
    table, cells, curves = train_study(tmp_path)
    row = cells.set_index("cell").loc["train"]
    assert row["transients"] == 4 * len(SEEDS)
    assert row["core_hours_per_seed"] == pytest.approx(450.0 / 3600)
    c = curves["train"]
    mu, norm, theta = transient(c["strain_since_reversal"].to_numpy())
    # every transient, mirrored or not, is the made-up one: the bin means of the model curve
    assert np.max(np.abs(c["A_norm"] - norm)) < 2e-3
    assert np.max(np.abs(c["theta_A_deg"] - theta)) < 1.5
    assert np.max(np.abs(c["mu"] - mu)) < 5e-3
    assert bool(table.set_index("cell").loc["train", "match"]) is True


def test_a_train_read_without_its_mirror_does_not_match_the_single_reversal(tmp_path):
    _, cells, curves = train_study(tmp_path, mirror=False)
    c = curves["train"]
    _, _, theta = transient(c["strain_since_reversal"].to_numpy())
    assert np.max(np.abs(c["theta_A_deg"] - theta)) > 10.0


def test_design_effect_compares_the_seed_standard_error_with_the_pooled_transients(tmp_path):
    _, cells, _ = train_study(tmp_path)
    row = cells.set_index("cell").loc["ref"]
    assert row["design_effect_A_norm"] == pytest.approx(1.0)    # one transient per seed: the same SE
    train = cells.set_index("cell").loc["train"]
    assert train["early_se_pooled_A_norm"] == pytest.approx(0.0, abs=1e-9)   # identical transients


def test_the_study_cli_fills_the_defaults_the_workflow_fills_from_the_schema():
    """python -m dem_study.bulk_cli reads a preset without Snakemake: its settings must be what
    Snakemake's schema validation gives the workflow (the schema is the defaults' one home)."""
    import copy

    import yaml
    from snakemake.utils import validate

    from campaign.schema_defaults import SCHEMA
    from dem_study import bulk_cells

    raw = yaml.safe_load((Path(__file__).resolve().parents[1] / "config" / "bulk_validation.yaml").read_text())
    raw = {**yaml.safe_load((Path(__file__).resolve().parents[1] / "config" / "quick.yaml").read_text()), **raw}
    for key in ("heaviside_strain", "steady_window", "match_se"):
        raw["accuracy"]["bulk_vs_walls"].pop(key, None)      # left to the defaults
    filled = copy.deepcopy(raw)
    validate(filled, str(SCHEMA))
    assert bulk_cells.settings(raw) == filled["accuracy"]["bulk_vs_walls"]
    assert bulk_cells.settings(raw)["match_se"] == 2.0 and bulk_cells.enabled({}) is False


def test_a_lammps_bulk_study_is_estimated_at_lammps_documented_throughput():
    import yaml

    from campaign import cost
    from campaign.schema_defaults import with_defaults
    from dem_study import bulk_cells

    root = Path(__file__).resolve().parents[1]
    config = with_defaults({**yaml.safe_load((root / "config" / "quick.yaml").read_text()),
                            **yaml.safe_load((root / "config" / "bulk_validation.yaml").read_text())})
    yade, lammps = bulk_cells.estimate(config), bulk_cells.estimate({**config, "engine": "lammps"})
    assert len(yade) > 0
    assert np.allclose(lammps["est_core_s"], yade["est_core_s"] / cost.LAMMPS_OVER_YADE, rtol=1e-12)
