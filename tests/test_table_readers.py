"""Tables read back by a later stage refuse a cut or ragged row; DEM series refuse a gap in their grid.

The tables are written by the pipeline's own code (model-made DEM cases,
``compare predict``'s tables written by pandas here in its layout) and then
damaged as a killed job or a lost block would damage them.
"""
import json
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

from claims.inputs import read_comparison
from compare.heldout import read_errors
from dem_contract import DEMInputError, read_series, synthetic
from dem_contract.tables import read_table
from model import default_params

PREDICTIONS = pd.DataFrame({
    "set": "all", "case": "p1_I0.001_s1", "group": "p1_I0.001", "seed": 1, "protocol": "heaviside",
    "source": ["dem", "model1", "model2"] * 4, "s_rev": np.repeat(np.linspace(0.0, 0.3, 4), 3),
    "A_xx": 0.01, "A_xy": -0.02, "A_norm": 0.0224, "theta_A": 121.7, "mu": 0.31})
ERRORS = pd.DataFrame({"set": "all", "level": "seed", "case": "p1_I0.001_s1", "group": "p1_I0.001",
                       "protocol": "heaviside", "in_sample": True, "model": ["model1", "model2"],
                       "status": "ok", "n_samples": 40, "rmse_mu": [0.01, 0.02]})


def cut_mid_row(path):
    """Cut the file in the middle of its last row (a job killed while writing it)."""
    text = path.read_text()
    last = text.rstrip("\n").rsplit("\n", 1)[1]
    path.write_text(text[: len(text) - 1 - len(last) // 2])
    return path


@pytest.fixture
def compare_dir(tmp_path):
    folder = tmp_path / "compare" / "all"
    folder.mkdir(parents=True)
    PREDICTIONS.to_csv(folder / "predictions.csv", index=False)
    ERRORS.to_csv(folder / "errors.csv", index=False)
    return tmp_path / "compare"


def test_complete_table_is_read_whole(compare_dir):
    assert len(read_table(compare_dir / "all" / "predictions.csv", ["set", "mu"])) == len(PREDICTIONS)
    assert len(read_comparison(compare_dir)) == len(PREDICTIONS)


def test_predictions_cut_in_the_middle_of_a_row_are_refused_by_line(compare_dir):
    path = cut_mid_row(compare_dir / "all" / "predictions.csv")
    with pytest.raises(DEMInputError, match=r"predictions\.csv: line 13 \(data row 12\) has \d+ field\(s\), the "
                                            r"header 12"):
        read_comparison(compare_dir)


def test_row_cut_after_its_last_separator_is_refused_by_its_missing_newline(compare_dir):
    path = compare_dir / "all" / "predictions.csv"
    path.write_text(path.read_text()[:-3])  # inside the last field: every field is still there
    with pytest.raises(DEMInputError, match=r"predictions\.csv: the last line \(line 13, data row 12\) does not end"):
        read_comparison(compare_dir)


def test_ragged_row_in_errors_is_refused_by_line(compare_dir):
    path = compare_dir / "all" / "errors.csv"
    lines = path.read_text().splitlines()
    lines[1] += ",extra"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(DEMInputError, match=r"errors\.csv: line 2 \(data row 1\) has 11 field\(s\), the header 10"):
        read_errors([path])


def test_quoted_commas_are_one_field(tmp_path):
    path = tmp_path / "notes.csv"
    pd.DataFrame({"key": ["a", "b"], "detail": ["one, two", "three"]}).to_csv(path, index=False)
    assert read_table(path, ["detail"])["detail"].tolist() == ["one, two", "three"]


@pytest.mark.slow
def test_claims_command_refuses_a_cut_predictions_table(compare_dir, tmp_path):
    cut_mid_row(compare_dir / "all" / "predictions.csv")
    result = subprocess.run([sys.executable, "-m", "claims", "--compare", str(compare_dir), "--dem", str(tmp_path),
                             "--out", str(tmp_path / "claims")],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode != 0
    assert "predictions.csv: line 13" in result.stderr, result.stderr[-2000:]


# --- gaps in a DEM series' sampling grid ---------------------------------------------------

@pytest.fixture
def case(tmp_path):
    return synthetic.write_case(tmp_path / "p1_I0.001_s1", default_params(), protocols=("heaviside",))


def drop_rows(path, start=60, n=30):
    """Remove ``n`` rows from the middle: t, strain and gammadot still agree across the gap."""
    df = pd.read_csv(path)
    df.drop(index=range(start, start + n)).to_csv(path, index=False)
    return path


def test_model_made_series_have_no_gap(case):
    for stage in ("preshear", "heaviside"):
        read_series(case / f"{stage}.csv")


def test_series_with_30_rows_missing_from_the_middle_is_refused(case):
    path = drop_rows(case / "heaviside.csv")
    with pytest.raises(DEMInputError, match=r"heaviside\.csv: a gap in the sampling grid between data rows 60 and "
                                            r"61 .*3 times the larger neighbouring step"):
        read_series(path)


def test_one_missing_row_is_refused_with_the_sidecar_grid(case):
    path = case / "heaviside.csv"
    t = pd.read_csv(path)["t"].to_numpy()
    side = json.loads(path.with_suffix(".json").read_text())
    coarse = float(np.max(np.diff(t)))
    # a YADE sidecar: sampling intervals in time steps of dt seconds, t in units of time_unit_s
    side.update(sampling_steps={"fine": 10, "coarse": 100, "every": 10}, dt=coarse / 100 * 2.0, time_unit_s=2.0)
    path.with_suffix(".json").write_text(json.dumps(side))
    read_series(path)
    drop_rows(path, start=len(t) - 5, n=1)
    with pytest.raises(DEMInputError, match=r"a gap in the sampling grid .*sidecar's sampling_steps"):
        read_series(path)


@pytest.mark.slow
def test_calibration_refuses_a_gappy_series_naming_it(tmp_path):
    dirs = synthetic.write_ensemble(tmp_path / "dem", default_params(), seeds=(1, 2), protocols=("heaviside",))
    drop_rows(dirs[1] / "heaviside.csv")
    result = subprocess.run([sys.executable, "-m", "calibrate", "--dem", *map(str, dirs), "--protocols", "heaviside",
                             "--out", str(tmp_path / "cal"), "--bootstrap", "0"],
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 2, result.stderr[-2000:]
    assert f"{dirs[1] / 'heaviside.csv'}: a gap in the sampling grid" in result.stderr
