"""External DEM data through ``python -m dem_contract import`` (docs/own-dem-data.md), on model-made runs.

The runs are written by the model itself (``dem_contract.synthetic``, the
calibration's defaults: the DEM's noise, a pre-shear from isotropy) and then
put into the minimal format a user brings: one CSV per run holding the whole
history, with only the required columns, a start from rest (the wall speed
steps from 0 at t = 0), and a metadata YAML.
"""
import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from calibrate import synthetic
from dem_contract import DEMInputError, read_series
from dem_contract.importer import MINIMAL_COLUMNS, import_cases
from model import default_params
from tests.helpers import run_main

ROOT = Path(__file__).resolve().parents[1]
PRESHEAR = 2.0


def run_cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", *args], cwd=cwd or ROOT, capture_output=True, text=True)


def run_package(package, *args):
    """``python -m package *args`` in-process (``helpers.run_main``): calibrate, compare and claims."""
    return run_main({"calibrate": "calibrate.__main__"}.get(package, f"{package}.cli"), args, package=package)


def minimal_runs(made: Path, out: Path, seed: int, protocols, mirror=False, extra=()):
    """The model-made case ``made`` as the minimal CSVs a user brings: one per run, pre-shear included, from rest."""
    pre = pd.read_csv(made / "preshear.csv")
    files = {}
    for protocol in protocols:
        run = pd.read_csv(made / f"{protocol}.csv").iloc[1:]      # its first row is the pre-shear's last
        whole = pd.concat([pre, run], ignore_index=True)[list(MINIMAL_COLUMNS) + list(extra)]
        whole.loc[0, "gammadot"] = 0.0                           # at rest at t = 0
        if mirror:                                               # a simulator shearing towards -x
            for c in ("strain", "gammadot", "A_xy", "sigma_xy"):
                whole[c] = -whole[c]
        name = f"seed{seed}_{protocol}.csv"
        whole.to_csv(out / name, index=False)
        files[protocol] = name
    return files


def reversal_strains(protocol, schedules):
    """The strains at which a run reverses (the pre-shear ends at ``PRESHEAR``; a schedule's segments follow)."""
    if protocol not in (schedules or {}):
        return [PRESHEAR]
    out, at, prev = [], PRESHEAR, 1
    for length, direction, *_ in schedules[protocol]:
        if direction != prev:
            out.append(at)
        at, prev = at + direction * length, direction
    return out


def write_external(tmp: Path, seeds=(1, 2, 3), protocols=("heaviside", "sinusoidal"), schedules=None, cell=None,
                   mirror=False, extra=(), costs=None, I=1e-3):
    """Model-made runs in the minimal format plus their metadata YAML under ``tmp``; returns the YAML's path."""
    made, ext = tmp / "made", tmp / "external"
    ext.mkdir(parents=True, exist_ok=True)
    runs_of = [*protocols, *(schedules or {})]
    sign = -1 if mirror else 1
    cases = []
    for s in seeds:
        case = synthetic.write_case(made / f"s{s}", default_params(), seed=s, preshear_strain=PRESHEAR,
                                    I=I, protocols=protocols, schedules=schedules)
        files = minimal_runs(case, ext, s, runs_of, mirror, extra)
        runs = [{"file": files[p], "protocol": p,
                 "reversals": [{"strain": sign * x} | ({"transition_strain": 0.1} if p == "sinusoidal" else {})
                               for x in reversal_strains(p, schedules)]}
                for p in runs_of]
        cases.append({"seed": s, "runs": runs} | ({"costs": costs} if costs else {}))
    meta = {"pressure": 1.0e5, "inertial_number": I, "simulator": "model-made test data", "cases": cases}
    if cell:
        meta["cell"] = cell
    (ext / "case.yaml").write_text(yaml.safe_dump(meta, sort_keys=False))
    return ext / "case.yaml"


# --------------------------------------------------------------------------- the reader: a start from rest


def test_reader_accepts_a_start_from_rest_and_still_refuses_a_strain_jump(tmp_path):
    t = np.arange(0.0, 10.0, 1.0)
    g = np.where(t == 0.0, 0.0, 1e-3)                 # the walls start at t = 0 from rest
    strain = np.concatenate([[0.0], 1e-3 * t[1:]])    # the rate stepped at once: the first step is 1e-3 dt
    d = pd.DataFrame({"t": t, "strain": strain, "gammadot": g})
    d.to_csv(tmp_path / "rest.csv", index=False)
    assert len(read_series(tmp_path / "rest.csv", ("t", "strain", "gammadot"))) == 10
    d.loc[5:, "strain"] += 0.3                          # a jump later in the run is still refused
    d.to_csv(tmp_path / "jump.csv", index=False)
    with pytest.raises(DEMInputError, match=r"jump\.csv: strain jumps by \+0\.301 between data rows 5 and 6"):
        read_series(tmp_path / "jump.csv", ("t", "strain", "gammadot"))


# --------------------------------------------------------------------------- import -> calibrate -> compare -> claims

CALIBRATE_OPTIONS = ["--bootstrap", "4", "--bootstrap-evals", "20", "--route2-evals", "40", "--min-bin-samples", "8",
                     "--profile-points", "0", "--no-figures"]


def pipeline(meta: Path, root: Path, sets: dict, protocols):
    """The packages' command lines on imported data: import (its own process), calibrate and compare per set, claims
    (in-process, ``run_package``); returns the DEM dirs."""
    done = run_cli("dem_contract", "import", "--meta", str(meta), "--out", str(root / "dem"))
    assert done.returncode == 0, done.stderr
    dirs = sorted(str(d) for d in (root / "dem").iterdir())
    labels = [Path(d).name for d in dirs]
    for name, trained in sets.items():
        done = run_package("calibrate", "--dem", *dirs, "--protocols", *trained, "--out", str(root / "cal" / name),
                       *CALIBRATE_OPTIONS)
        assert done.returncode == 0, done.stdout[-2000:] + done.stderr
        done = run_package("compare", "predict", "--dem", *dirs, "--params", str(root / "cal" / name / "params.yaml"),
                       "--set", name, "--protocols", *protocols, "--train-cases", *labels,
                       "--train-protocols", *trained, "--out", str(root / "compare" / name),
                       "--figures")   # none drawn (as calibrate's --no-figures): no test reads them, 1.2 s each
        assert done.returncode == 0, done.stdout[-2000:] + done.stderr
    done = run_package("claims", "--compare", str(root / "compare"), "--dem", *dirs, "--protocols", *protocols,
                   "--calibration", str(root / "cal" / "all" / "params.yaml"), "--sets", *sets,
                   "--resamples", "200", "--out", str(root / "claims"))
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr
    return dirs


SCHEDULES = {"double": [(0.15, -1), (0.4, 1)]}    # a double reversal: back after 0.15 strain
COSTS = {"pack": {"cpu_time_s": 100.0}, "preshear": {"cpu_time_s": 200.0}, "heaviside": {"cpu_time_s": 30.0},
         "double": {"cpu_time_s": 30.0}}


@pytest.fixture(scope="module")
def from_rest(tmp_path_factory):
    """Three seeds started from rest, a Heaviside and a sinusoidal run each, through the whole chain."""
    root = tmp_path_factory.mktemp("from_rest")
    meta = write_external(root, cell={"H_over_d": 12, "W_over_H": 4})
    dirs = pipeline(meta, root, {"all": ["heaviside", "sinusoidal"], "heaviside_only": ["heaviside"]},
                    ["heaviside", "sinusoidal"])
    return root, dirs


@pytest.fixture(scope="module")
def other_cell(tmp_path_factory):
    """Three seeds of a tall narrow cell (H = 37 d, W = 24 d) sheared towards -x, a Heaviside and a double reversal."""
    root = tmp_path_factory.mktemp("other_cell")
    meta = write_external(root, protocols=("heaviside",), schedules=SCHEDULES, cell={"H_over_d": 37, "W_over_H": 0.65},
                          mirror=True, extra=("gap",), costs=COSTS)
    dirs = pipeline(meta, root, {"all": ["heaviside", "double"], "heaviside_only": ["heaviside"]},
                    ["heaviside", "double"])
    return root, dirs


def test_import_keeps_the_start_from_rest_and_states_the_reversal(from_rest):
    root, dirs = from_rest
    case = Path(dirs[0])
    pre = pd.read_csv(case / "preshear.csv")
    assert pre["gammadot"].iloc[0] == 0.0 and pre["strain"].iloc[-1] == pytest.approx(PRESHEAR)
    side = json.loads((case / "sinusoidal.json").read_text())
    assert side["reversal_strain"] == pytest.approx(PRESHEAR)
    assert side["reversals"] == [{"t": side["reversal_t"], "strain": side["reversal_strain"], "direction": -1,
                                  "transition": "half_cosine", "transition_strain": 0.1}]
    assert pd.read_csv(case / "heaviside.csv")["t"].iloc[0] > side["reversal_t"]
    assert json.loads((case / "scene.json").read_text())["geometry"] == {"H_over_d": 12.0, "W_over_H": 4.0}


def test_imported_runs_are_followed_by_both_models_within_the_noise(from_rest):
    root, _ = from_rest
    err = pd.read_csv(root / "compare" / "all" / "errors.csv")
    seeds = err[err["level"] == "seed"]
    assert set(seeds["protocol"]) == {"heaviside", "sinusoidal"} and len(seeds) == 3 * 2 * 2
    assert (seeds["status"] == "ok").all()
    # the model made the data: what is left is the noise (0.0125 per fabric component, 0.04 in mu)
    assert seeds["rmse_A_norm"].max() < 2 * np.sqrt(2) * 0.0125 and seeds["rmse_mu"].max() < 0.06


def test_claims_of_imported_data_name_the_unknown_cost(from_rest):
    root, _ = from_rest
    table = pd.read_csv(root / "claims" / "paper_claims.csv")
    assert len(table) >= 10 and table["verdict"].notna().all()
    power = pd.read_csv(root / "claims" / "power.csv")
    assert (power["core_hours"] == "unknown").all()            # no pack stage, no timing sidecar
    section = (root / "claims" / "README_section.md").read_text()
    assert "unknown core-hours" in section and "nan" not in section.split("### Power")[1].split("\n- the")[0]


def test_import_mirrors_a_pre_shear_towards_minus_x_and_splits_a_double_reversal(other_cell):
    root, dirs = other_cell
    case = Path(dirs[0])
    pre = pd.read_csv(case / "preshear.csv")
    assert (pre["gammadot"].iloc[1:] > 0).all() and pre["strain"].iloc[-1] == pytest.approx(PRESHEAR)
    assert json.loads((case / "preshear.json").read_text())["mirrored"] is True
    side = json.loads((case / "double.json").read_text())
    assert [(r["strain"], r["direction"]) for r in side["reversals"]] == [(pytest.approx(PRESHEAR), -1),
                                                                          (pytest.approx(PRESHEAR - 0.15), 1)]
    assert json.loads((case / "scene.json").read_text())["geometry"] == {"H_over_d": 37.0, "W_over_H": 0.65}
    err = pd.read_csv(root / "compare" / "heaviside_only" / "errors.csv")
    out = err[(err["level"] == "seed") & ~err["in_sample"]]
    assert set(out["protocol"]) == {"double_r1", "double_r2"} and (out["status"] == "ok").all()
    assert out["rmse_A_norm"].max() < 2 * np.sqrt(2) * 0.0125


def test_claims_of_a_case_with_costs_state_its_core_hours(other_cell):
    root, _ = other_cell
    power = pd.read_csv(root / "claims" / "power.csv")
    seed_cpu = 100.0 + 200.0 + power["transients_per_seed"] * 30.0      # pack + pre-shear + scored transients
    expected = power["seeds_needed"] * seed_cpu / 3600.0
    assert np.allclose(power["core_hours"].astype(float), expected, rtol=1e-5)
    assert (power["disks_per_seed"] == "unknown").all()                  # the metadata give no N


# --------------------------------------------------------------------------- bad metadata, named


def test_import_names_a_reversal_strain_the_run_never_reaches(tmp_path):
    meta = write_external(tmp_path, seeds=(1,), protocols=("heaviside",))
    text = yaml.safe_load(meta.read_text())
    text["cases"][0]["runs"][0]["reversals"][0]["strain"] = 9.0
    meta.write_text(yaml.safe_dump(text))
    with pytest.raises(DEMInputError, match=r"seed1_heaviside\.csv: reversal 1 at strain 9: the run's strain never "
                                            r"reaches it"):
        import_cases(meta, tmp_path / "dem")


def test_import_names_a_missing_metadata_key_and_exits_2(tmp_path):
    (tmp_path / "case.yaml").write_text("pressure: 1.0e5\ncases: []\n")
    done = run_cli("dem_contract", "import", "--meta", str(tmp_path / "case.yaml"), "--out", str(tmp_path / "dem"))
    assert done.returncode == 2 and "case.yaml: missing key 'inertial_number'" in done.stderr


# --------------------------------------------------------------------------- what the contract implies, or refused


def flip(column):
    def edit(run):
        run[column] = -run[column]
    return edit


def double_mu(run):
    run["mu"] = 2 * run["sigma_xy"].abs() / run["p"]


def in_pascal(run):
    run[["sigma_xy", "p"]] *= 1.0e5


@pytest.mark.parametrize("edit, words", [
    (flip("sigma_xy"), r"seed1_heaviside\.csv: run heaviside of seed 1: column 'sigma_xy' has the wrong sign in the "
                       r"pre-shear's steady window \(data rows \d+-\d+, rate > 0\)"),
    (flip("A_xy"), r"seed1_heaviside\.csv: run heaviside of seed 1: column 'A_xy' has the wrong sign in the "
                   r"pre-shear's steady window \(data rows \d+-\d+, rate > 0\)"),
    (double_mu, r"seed1_heaviside\.csv: column 'mu' = [\d.]+ at data row \d+ but \|sigma_xy\|/p = [\d.]+ there"),
    (in_pascal, r"seed1_heaviside\.csv: column 'sigma_xy' = .* is not of order 1 .* looks like SI \(Pa\)"),
], ids=["sigma_xy sign-flipped", "A_xy sign-flipped", "mu twice |sigma_xy|/p", "stresses in Pa"])
def test_import_refuses_a_run_that_breaks_the_contract_naming_the_input_file_and_writes_nothing(tmp_path, edit, words):
    """Issue 33's four silent acceptances, each in one of two runs of one seed: the good import passes, the edited
    one exits 2 naming the input file (and the column, run and rows), and leaves ``--out`` as it was."""
    meta = write_external(tmp_path, seeds=(1,), protocols=("heaviside", "sinusoidal"))
    done = run_main("dem_contract.__main__", ["import", "--meta", meta, "--out", tmp_path / "good"])
    assert done.returncode == 0, done.stderr
    path = meta.parent / "seed1_heaviside.csv"
    run = pd.read_csv(path)
    edit(run)
    run.to_csv(path, index=False)
    (tmp_path / "dem").mkdir()
    (tmp_path / "dem" / "kept.txt").write_text("an earlier file\n")
    done = run_main("dem_contract.__main__", ["import", "--meta", meta, "--out", tmp_path / "dem"])
    assert done.returncode == 2
    assert re.search(words, done.stderr), done.stderr
    assert [p.name for p in (tmp_path / "dem").iterdir()] == ["kept.txt"]
    assert not any(p.name.startswith(".dem.") for p in tmp_path.iterdir())


def test_a_refused_import_leaves_no_folder_it_created(tmp_path):
    """An --out whose parents do not exist yet: a refused import leaves none of them."""
    meta = write_external(tmp_path, seeds=(1,), protocols=("heaviside",))
    run = pd.read_csv(meta.parent / "seed1_heaviside.csv")
    flip("sigma_xy")(run)
    run.to_csv(meta.parent / "seed1_heaviside.csv", index=False)
    done = run_main("dem_contract.__main__", ["import", "--meta", meta, "--out", tmp_path / "new" / "dem"])
    assert done.returncode == 2 and "seed1_heaviside.csv" in done.stderr
    assert not (tmp_path / "new").exists()


def test_a_second_import_replaces_its_cases_and_keeps_the_others(tmp_path):
    """Imported cases are moved into --out whole: a case imported again replaces its folder; other folders stay."""
    meta = write_external(tmp_path, seeds=(1,), protocols=("heaviside", "sinusoidal"))
    out = tmp_path / "dem"
    (out / "p1_I0.001_s9").mkdir(parents=True)
    assert run_main("dem_contract.__main__", ["import", "--meta", meta, "--out", out]).returncode == 0
    text = yaml.safe_load(meta.read_text())
    text["cases"][0]["runs"] = text["cases"][0]["runs"][:1]       # the heaviside run alone
    meta.write_text(yaml.safe_dump(text))
    assert run_main("dem_contract.__main__", ["import", "--meta", meta, "--out", out]).returncode == 0
    assert sorted(p.name for p in out.iterdir()) == ["p100000_I0.001_s1", "p1_I0.001_s9"]
    assert sorted(p.name for p in (out / "p100000_I0.001_s1").glob("*.csv")) == ["heaviside.csv", "preshear.csv"]


# --------------------------------------------------------------------------- branched runs: a pre-shear file, branches


def as_branches(meta: Path, restart=False) -> Path:
    """The one-file-per-run case of ``write_external`` (one seed) as a user with branched runs brings it.

    The pre-shear in its own file (the rows up to the first reversal, that row included) and each run as a
    branch from the reversal on (its first row the state at the reversal); with ``restart``, the branches'
    ``t`` and ``strain`` start at 0 and their reversal strains are counted from the branch. Returns the YAML.
    """
    text = yaml.safe_load(meta.read_text())
    (case,) = text["cases"]
    n_pre = len(pd.read_csv(next((meta.parent.parent / "made").rglob("preshear.csv"))))
    whole = pd.read_csv(meta.parent / case["runs"][0]["file"])
    whole.iloc[:n_pre].to_csv(meta.parent / "seed1_preshear.csv", index=False)
    case["preshear"] = "seed1_preshear.csv"
    for run in case["runs"]:
        branch = pd.read_csv(meta.parent / run["file"]).iloc[n_pre - 1:].reset_index(drop=True)
        if restart:
            s0 = branch["strain"].iloc[0]
            branch = branch.assign(t=branch["t"] - branch["t"].iloc[0], strain=branch["strain"] - s0)
            run["reversals"] = [{**r, "strain": float(r["strain"] - s0)} for r in run["reversals"]]
        run["file"] = run["file"].replace(".csv", "_branch.csv")
        branch.to_csv(meta.parent / run["file"], index=False)
    out = meta.with_name("branched.yaml")
    out.write_text(yaml.safe_dump(text, sort_keys=False))
    return out


def contract_files(case: Path) -> dict:
    """The files of an imported case: CSVs as bytes, sidecars as dicts without ``source_file``."""
    return {p.name: p.read_bytes() if p.suffix == ".csv" else
            {k: v for k, v in json.loads(p.read_text()).items() if k != "source_file"}
            for p in sorted(case.iterdir())}


@pytest.mark.parametrize("mirror", [False, True], ids=["towards +x", "towards -x"])
def test_one_history_as_one_file_per_run_or_as_pre_shear_and_branches_imports_to_the_same_files(tmp_path, mirror):
    """A Heaviside, a sinusoidal and a double reversal of one seed: the branched form writes the same bytes."""
    meta = write_external(tmp_path, seeds=(1,), protocols=("heaviside", "sinusoidal"), schedules=SCHEDULES,
                          mirror=mirror)
    (one,) = import_cases(meta, tmp_path / "one")
    (branched,) = import_cases(as_branches(meta), tmp_path / "branched")
    assert contract_files(branched) == contract_files(one)
    assert len(contract_files(one)) == 9            # the pre-shear and three runs, their sidecars, scene.json
    assert json.loads((branched / "preshear.json").read_text())["source_file"] == "seed1_preshear.csv"


def test_branches_whose_clock_and_strain_restart_at_zero_import_on_the_pre_shears(tmp_path):
    meta = write_external(tmp_path, seeds=(1,), protocols=("heaviside",), schedules=SCHEDULES, mirror=True)
    (one,) = import_cases(meta, tmp_path / "one")
    (branched,) = import_cases(as_branches(meta, restart=True), tmp_path / "branched")
    for name in ("preshear", "heaviside", "double"):
        a, b = pd.read_csv(one / f"{name}.csv"), pd.read_csv(branched / f"{name}.csv")
        assert list(a.columns) == list(b.columns)
        assert np.allclose(a.to_numpy(float), b.to_numpy(float), rtol=1e-12, atol=1e-12, equal_nan=True)
        side_a, side_b = (json.loads((d / f"{name}.json").read_text()) for d in (one, branched))
        assert [(r["t"], r["strain"]) for r in side_b.get("reversals", [])] == \
            [(pytest.approx(r["t"], abs=1e-12), pytest.approx(r["strain"], abs=1e-12)) for r in side_a.get("reversals", [])]


def late_by_a_row(text, ext):
    branch = pd.read_csv(ext / "seed1_heaviside_branch.csv")
    branch.iloc[1:].to_csv(ext / "seed1_heaviside_branch.csv", index=False)


def from_another_state(text, ext):
    branch = pd.read_csv(ext / "seed1_heaviside_branch.csv")
    branch.loc[0, "A_xy"] -= 0.01
    branch.to_csv(ext / "seed1_heaviside_branch.csv", index=False)


def reversing_elsewhere(text, ext):
    text["cases"][0]["runs"][0]["reversals"][0]["strain"] = 1.5


def no_file_name(text, ext):
    text["cases"][0]["preshear"] = 3


@pytest.mark.parametrize("edit, words", [
    (late_by_a_row, r"seed1_heaviside_branch\.csv: run heaviside of seed 1: column 't' = [\d.]+ in the first data "
                    r"row: a branch's first row is the state at the reversal, its t the pre-shear's last \([\d.]+, "
                    r".*seed1_preshear\.csv\) or 0"),
    (from_another_state, r"seed1_heaviside_branch\.csv: run heaviside of seed 1: column 'A_xy' = -?[\d.]+ in the "
                         r"first data row, the pre-shear's last row \(.*seed1_preshear\.csv\) -?[\d.]+"),
    (reversing_elsewhere, r"seed1_heaviside_branch\.csv: run heaviside of seed 1: reversal 1 at strain 1\.5: a "
                          r"branch starts at its first reversal, but its first data row is at strain 2"),
    (no_file_name, r"branched\.yaml: cases\[0\]: preshear = 3: expected the pre-shear's file"),
], ids=["a row late", "another state", "first reversal elsewhere", "preshear not a file name"])
def test_import_refuses_a_branch_that_does_not_start_at_the_pre_shears_end_naming_file_column_and_run(
        tmp_path, edit, words):
    ext = write_external(tmp_path, seeds=(1,), protocols=("heaviside",)).parent
    meta = as_branches(ext / "case.yaml")
    text = yaml.safe_load(meta.read_text())
    edit(text, ext)
    meta.write_text(yaml.safe_dump(text, sort_keys=False))
    done = run_main("dem_contract.__main__", ["import", "--meta", meta, "--out", tmp_path / "dem"])
    assert done.returncode == 2
    assert re.search(words, done.stderr), done.stderr
    assert not (tmp_path / "dem").exists()
