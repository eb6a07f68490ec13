"""The engines' agreement table (dem_study/engines.py, ``python -m dem_study engines``) on released DEM runs.

The bulk-vs-walls validation release (data/bulk-validation-reconciled: 4 + 4 YADE seeds of the W = 4H wall
cell and the narrow cell, kappa 700, I 3e-4) stands in for the two engines: with the study's windows the
table repeats the study's own published differences, z and transient RMS; the narrow cell's seeds against a
copy of themselves with mu shifted by a known amount give that shift, its z, and a failed agreement."""
import math
import shutil

import numpy as np
import pandas as pd
import pytest
import yaml

from dem_contract import release
from dem_study import engines
from dem_study.analysis import strain_edges
from dem_study.cli import main
from tests.helpers import ROOT

RELEASE = ROOT / "data" / "bulk-validation-reconciled"
PUBLISHED = RELEASE / "published" / "bulk_vs_walls.csv"
WIDE, NARROW = "W4H-H37", "narrow-H37-W18"
SEEDS = (1, 2, 3, 4)
# the study's windows (the release's config: accuracy.bulk_vs_walls): steady over the last 0.6 of the
# pre-shear, transients compared over the whole Heaviside run (0.3 strain) in bins of 0.01
STUDY = ["--steady-window", "0.6", "--early-strain", "0.3", "--transient-bin", "0.01"]

pytestmark = pytest.mark.skipif(not RELEASE.is_dir(), reason="data/bulk-validation-reconciled is not in data/")


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    """The release's two cells as the two engines, through the command line (the release restored by the tool)."""
    out = tmp_path_factory.mktemp("engines")
    code = main(["engines", "--yade", str(RELEASE), "--yade-cases", f"{WIDE}_*", "--lammps", str(RELEASE / "cases"),
                 "--lammps-cases", f"{NARROW}_*", "--stage", "heaviside", "--out", str(out), "--name", "v", *STUDY])
    assert code == 0
    return out, pd.read_csv(out / "v_agreement.csv").set_index("quantity")


@pytest.fixture(scope="module")
def narrow(tmp_path_factory):
    """The narrow cell's four seeds restored as finished case folders."""
    root = tmp_path_factory.mktemp("narrow")
    return [release.restore_case(RELEASE, f"{NARROW}_s{s}", root / f"{NARROW}_s{s}") for s in SEEDS]


def test_two_cells_as_engines_repeat_the_bulk_studys_published_means_differences_and_z(study):
    """Steady seed means, SEs, differences and z equal the published bulk_vs_walls.csv (6 digits), and the
    agreement follows the study's rule: Z fails at 2 SE (z 2.42, the study's `failing`) but not at
    Bonferroni's family level, 2.58."""
    _, table = study
    pub = pd.read_csv(PUBLISHED).set_index("cell")
    for q in ("mu", "A_norm", "theta_A_deg", "phi", "Z"):
        row = table.loc[q]
        row = row[row["kind"] == "steady"].iloc[0] if isinstance(row, pd.DataFrame) else row
        assert row["yade_mean"] == pytest.approx(pub.loc[WIDE, q], rel=1e-5)
        assert row["yade_se"] == pytest.approx(pub.loc[WIDE, f"{q}_se"], rel=1e-5)
        assert row["lammps_mean"] == pytest.approx(pub.loc[NARROW, q], rel=1e-5)
        assert row["difference"] == pytest.approx(pub.loc[NARROW, f"d_{q}"], rel=1e-4, abs=1e-9)
        assert row["z"] == pytest.approx(pub.loc[NARROW, f"z_{q}"], rel=1e-4)
        assert row["yade_seeds"] == row["lammps_seeds"] == 4
        assert bool(row["agrees"]) == (q not in pub.loc[NARROW, "failing"].split(", "))
        assert bool(row["agrees_family"]) == (abs(row["z"]) <= 2.5758)
    assert engines.family_z() == pytest.approx(2.5758, abs=1e-4)


def test_the_transient_rows_repeat_the_studys_rms_difference_and_seed_noise(study):
    """Over the whole Heaviside run (the study's window) the RMS difference and RMS noise of mu, |A|, theta_A
    are the published transient_<q>_rms and _noise; each agrees when the RMS is at most twice the noise."""
    _, table = study
    pub = pd.read_csv(PUBLISHED).set_index("cell").loc[NARROW]
    tr = table[table["kind"] == "transient"]
    assert list(tr.index) == ["mu", "A_norm", "theta_A_deg"]
    for q, row in tr.iterrows():
        assert row["rms_difference"] == pytest.approx(pub[f"transient_{q}_rms"], rel=1e-4)
        assert row["rms_noise"] == pytest.approx(pub[f"transient_{q}_noise"], rel=1e-4)
        # the CSV holds 6 digits
        assert row["noise_ratio"] == pytest.approx(row["rms_difference"] / row["rms_noise"], rel=1e-5)
        assert bool(row["agrees"]) == (row["rms_difference"] <= 2 * row["rms_noise"])


def test_the_cost_table_holds_core_hours_and_throughput_from_the_released_sidecars(study):
    """Core-hours per seed as the study published them; particle-steps per CPU second of the pre-shear and
    Heaviside run from the released case.yaml's steps and CPU seconds: N sum(steps) / sum(CPU s)."""
    out, _ = study
    cost = pd.read_csv(out / "v_cost.csv").set_index("engine")
    pub = pd.read_csv(PUBLISHED).set_index("cell")
    for engine, cell in (("yade", WIDE), ("lammps", NARROW)):
        assert cost.loc[engine, "core_hours_per_seed"] == pytest.approx(pub.loc[cell, "core_hours_per_seed"], rel=1e-5)
        steps = cpu = 0.0
        for s in SEEDS:
            case = yaml.safe_load((RELEASE / "cases" / f"{cell}_s{s}" / "case.yaml").read_text())
            costs = case["cases"][0]["costs"]
            steps += case["N"] * (costs["preshear"]["steps"] + costs["heaviside"]["steps"])
            cpu += costs["preshear"]["cpu_time_s"] + costs["heaviside"]["cpu_time_s"]
        assert cost.loc[engine, "particle_steps_per_cpu_s"] == pytest.approx(steps / cpu, rel=1e-5)
        assert cost.loc[engine, "engine_recorded"] == "yade" and cost.loc[engine, "seeds"] == 4


def test_the_markdown_and_summary_name_the_rule_the_scene_difference_and_the_failing_quantity(study):
    out, _ = study
    md = (out / "v_agreement.md").read_text()
    assert "| Z |" in md and "**no** | yes |" in md and "2.58" in md
    assert "`geometry.W_over_H: 4.0 -> 0.5`" in md
    info = pd.read_json(out / "v_agreement.json", typ="series")
    assert info["differ"] == ["steady Z"] and info["reference"] == "yade"
    assert (out / "v_transients.png").stat().st_size > 10_000


def shifted_copy(cases, into, delta):
    """Copies of the case folders with ``delta`` added to mu in the pre-shear and the reversal run."""
    into.mkdir()
    for d in cases:
        shutil.copytree(d, into / d.name)
        for stage in ("preshear", "heaviside"):
            path = into / d.name / f"{stage}.csv"
            frame = pd.read_csv(path)
            frame["mu"] += delta
            frame.to_csv(path, index=False, float_format="%.17g")
    return into


@pytest.mark.parametrize("delta", [0.0, 0.05])
def test_one_engine_shifted_by_a_known_mu_gives_that_difference_its_z_and_fails_only_when_shifted(narrow, tmp_path,
                                                                                                    delta):
    """The narrow cell against a copy of itself with mu + delta: the steady difference is delta and
    z = delta / sqrt(2 SE^2); the early transient's RMS and mean difference are delta, its noise that of
    the unshifted pair. delta = 0.05 (about 9 SE) fails mu, steady and transient; the rest agree, z = 0."""
    yade = narrow[0].parent
    lammps = shifted_copy(narrow, tmp_path / "lammps", delta)
    cases = engines.cases_table({"yade": narrow, "lammps": sorted(lammps.iterdir())})
    pairs, cells, curves = engines.compare(cases, "heaviside", strain_edges(0.3, 0.01), 0.1)
    table = engines.agreement_table(pairs, curves, 0.1)
    steady = table[table["kind"] == "steady"].set_index("quantity")
    tr = table[table["kind"] == "transient"].set_index("quantity")
    se = steady.loc["mu", "yade_se"]
    assert steady.loc["mu", "lammps_se"] == pytest.approx(se)
    assert steady.loc["mu", "difference"] == pytest.approx(delta, abs=1e-12)
    assert steady.loc["mu", "z"] == pytest.approx(delta / math.sqrt(2 * se**2), abs=1e-9)
    assert tr.loc["mu", "rms_difference"] == pytest.approx(delta, abs=1e-12)
    assert tr.loc["mu", "difference"] == pytest.approx(delta, abs=1e-12)
    noise = np.sqrt(2) * np.sqrt(np.mean(np.square(engines.early(curves, 0.1)["yade"]["mu_se"])))
    assert tr.loc["mu", "rms_noise"] == pytest.approx(noise)
    shifted = delta > 0
    assert bool(steady.loc["mu", "agrees"]) is not shifted and bool(steady.loc["mu", "agrees_family"]) is not shifted
    assert bool(tr.loc["mu", "agrees"]) is not shifted
    others = table[table["quantity"] != "mu"]
    assert others["agrees"].all() and np.allclose(steady.drop(index="mu")["z"], 0.0)
    assert yade.is_dir()


def test_an_engine_folder_holding_two_settings_is_refused_naming_the_key(narrow, tmp_path, capsys):
    """Cases of two cells in one engine's folder: exit 2, the differing scene key named."""
    mixed = tmp_path / "mixed"
    mixed.mkdir()
    shutil.copytree(narrow[0], mixed / narrow[0].name)
    wide = release.restore_case(RELEASE, f"{WIDE}_s1", mixed / f"{WIDE}_s1")
    assert wide.is_dir()
    code = main(["engines", "--yade", str(mixed), "--lammps", str(narrow[0].parent), "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 2 and "geometry.W_over_H" in err and "--yade-cases" in err
    assert not (tmp_path / "o").exists()


def test_a_folder_without_the_stage_is_named(narrow, tmp_path, capsys):
    code = main(["engines", "--yade", str(narrow[0].parent), "--lammps", str(narrow[0].parent), "--stage",
                 "sinusoidal", "--out", str(tmp_path / "o")])
    assert code == 2 and "no finished case with a pre-shear and a sinusoidal run" in capsys.readouterr().err
