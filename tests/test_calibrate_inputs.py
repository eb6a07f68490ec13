"""Bad DEM input stops the calibration with an error naming the file and the problem (never a fit of garbage).

The contract's own checks (missing file or column, NaN, too few rows, time not
increasing) are tested once, on ``dem_contract.read_series``: tests/test_dem_contract.py.
"""
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from calibrate import io, synthetic
from model import default_params
from tests.helpers import run_main

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def good_case(tmp_path_factory):
    root = tmp_path_factory.mktemp("dem")
    return synthetic.write_case(root / "p1_I0.001_s1", default_params(), seed=1, preshear_strain=3.0)


def copy_case(src, dst):
    dst.mkdir(parents=True)
    for f in src.iterdir():
        (dst / f.name).write_bytes(f.read_bytes())
    return dst


def test_good_case_reads_and_reports_its_steady_state(good_case):
    case = io.read_case(good_case)
    st = case.preshear.meta["steady"]
    assert st["A_xy"] < 0 and 0.1 < st["mu"] < 0.4
    assert set(case.runs) == {"heaviside", "sinusoidal"}


def test_run_that_never_reached_steady_state(tmp_path):
    # a quiet run (a large cell) stopped at strain 0.6, while the fabric still grows from isotropy
    case = synthetic.write_case(tmp_path / "p1_I0.001_s1", default_params(), seed=1, preshear_strain=0.6,
                                fabric_noise=0.002, mu_noise=0.005)
    with pytest.raises(io.DEMInputError, match=r"preshear\.csv: the pre-shear never reached steady state"):
        io.read_cases([case])


def test_seeds_whose_mean_still_drifts_are_an_error_naming_their_files(tmp_path):
    # three seeds all stopped while the fabric still grows: the ensemble mean drifts too
    cases = [synthetic.write_case(tmp_path / f"p1_I0.001_s{k}", default_params(), seed=k, preshear_strain=0.6,
                                  fabric_noise=0.002, mu_noise=0.005) for k in (1, 2, 3)]
    with pytest.raises(io.DEMInputError, match=r"the mean of 3 seeds of p1_I0\.001 .*never reached steady state"):
        io.read_cases(cases)


def test_reversal_file_without_a_reversal(good_case, tmp_path):
    case = copy_case(good_case, tmp_path / "p1_I0.001_s1")
    df = pd.read_csv(case / "heaviside.csv")
    df["gammadot"] = np.abs(df["gammadot"])
    df["strain"] = 2 * df["strain"].iloc[0] - df["strain"]  # the strain follows the rate (the contract)
    df.to_csv(case / "heaviside.csv", index=False)
    with pytest.raises(io.DEMInputError, match=r"heaviside\.csv: 'gammadot' never takes the sign opposite"):
        io.read_case(case, protocols=("heaviside",))


def test_command_line_exits_2_naming_the_file(good_case, tmp_path):
    case = copy_case(good_case, tmp_path / "p1_I0.001_s1")
    df = pd.read_csv(case / "heaviside.csv")
    df.loc[3, "A_xx"] = np.inf
    df.to_csv(case / "heaviside.csv", index=False)
    out = tmp_path / "cal"
    r = subprocess.run([sys.executable, "-m", "calibrate", "--dem", str(case), "--out", str(out)],
                       cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert r.returncode == 2
    assert "heaviside.csv: column 'A_xx'" in r.stderr
    assert not (out / "params.yaml").exists()


def bad_fabric(good_case, tmp_path):
    case = copy_case(good_case, tmp_path / "p1_I0.001_s1")
    df = pd.read_csv(case / "heaviside.csv")
    df.loc[3, "A_xx"] = np.inf
    df.to_csv(case / "heaviside.csv", index=False)
    return case, "heaviside.csv: column 'A_xx'"


def no_such_case(good_case, tmp_path):
    return tmp_path / "p1_I0.001_s9", "p1_I0.001_s9"


@pytest.mark.parametrize("refusal", [bad_fabric, no_such_case], ids=["bad DEM file", "missing case"])
def test_a_refused_calibration_leaves_no_out_folder_it_created(good_case, tmp_path, refusal):
    """Issue 33: every refused calibrate left an empty --out (and its new parents); an --out that existed stays."""
    case, words = refusal(good_case, tmp_path)
    r = run_main("calibrate.__main__", ["--dem", case, "--out", tmp_path / "new" / "cal"])
    assert r.returncode == 2 and words in r.stderr
    assert not (tmp_path / "new").exists()
    (tmp_path / "old").mkdir()
    r = run_main("calibrate.__main__", ["--dem", case, "--out", tmp_path / "old"])
    assert r.returncode == 2 and (tmp_path / "old").is_dir()


def test_cases_with_different_protocols_are_read_each_with_its_own_runs(good_case, tmp_path):
    # a campaign may run the sinusoidal reversal for some seeds only: each run present is one transient
    both = copy_case(good_case, tmp_path / "p1_I0.001_s1")
    heaviside_only = copy_case(good_case, tmp_path / "p1_I0.001_s2")
    (heaviside_only / "sinusoidal.csv").unlink()
    (heaviside_only / "sinusoidal.json").unlink()
    cases = io.read_cases([both, heaviside_only])
    assert [set(c.runs) for c in cases] == [{"heaviside", "sinusoidal"}, {"heaviside"}]


def test_a_protocol_no_case_holds_is_an_error_naming_it(good_case, tmp_path):
    case = copy_case(good_case, tmp_path / "p1_I0.001_s1")
    (case / "sinusoidal.csv").unlink()
    with pytest.raises(io.DEMInputError, match=r"no case holds a sinusoidal run"):
        io.read_cases([case])
    with pytest.raises(io.DEMInputError, match=r"p1_I0\.001_s1: no reversal run of the protocols sinusoidal"):
        io.read_case(case, protocols=("sinusoidal",))
