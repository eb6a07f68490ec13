"""The DEM contract's reader (dem_contract): every bad file is a DEMInputError naming the file and the problem.

The stages add their own checks on top (tests/test_calibrate_inputs.py,
tests/test_compare.py); their command lines turn this error into exit status 2.
"""
import numpy as np
import pandas as pd
import pytest

from dem_contract import CONTRACT_COLUMNS, DEMInputError, read_series, read_sidecar


def write_run(path, n=60, **changes):
    """A well-formed contract CSV of ``n`` rows, with columns replaced by ``changes``.

    Physical values: time and strain increase, strain = integral of gammadot (0.01 per
    unit time), |A_ij| < 1/2, p > 0 and mu = |sigma_xy|/p within its range.
    """
    df = pd.DataFrame({c: np.linspace(0.01, 1.0, n) for c in CONTRACT_COLUMNS})
    df["t"] = np.arange(1.0, n + 1.0)
    df["gammadot"] = 0.01
    df["strain"] = 0.01 * (df["t"] - 1.0)
    df["A_xx"], df["A_xy"] = np.linspace(-0.02, -0.01, n), np.linspace(0.03, 0.05, n)
    df["sigma_xy"], df["p"] = np.linspace(0.2, 0.3, n), np.linspace(0.9, 1.1, n)
    df["mu"] = df["sigma_xy"].abs() / df["p"]
    for c, v in changes.items():
        df[c] = v
    df.to_csv(path, index=False)
    return path


def edited_run(path, columns, value, row=None):
    """``write_run``'s run with ``columns`` set to ``value`` (or to ``value(old values)``) in ``row`` (default all)."""
    write_run(path)
    df = pd.read_csv(path)
    rows = df.index if row is None else [row]
    df.loc[rows, columns] = value(df.loc[rows, columns]) if callable(value) else value
    df.to_csv(path, index=False)
    return path


def test_a_good_run_reads_with_the_asked_columns_as_floats(tmp_path):
    data = read_series(write_run(tmp_path / "preshear.csv"), min_samples=50)
    assert list(data.columns) == list(CONTRACT_COLUMNS) and len(data) == 60
    assert (data.dtypes == float).all()
    assert list(read_series(tmp_path / "preshear.csv", columns=("t", "mu")).columns) == ["t", "mu"]


def test_missing_file_is_named_with_what_was_expected(tmp_path):
    with pytest.raises(DEMInputError, match=r"sinusoidal\.csv: file not found \(expected the sinusoidal run of the case\)"):
        read_series(tmp_path / "sinusoidal.csv", what="the sinusoidal run of the case")
    (tmp_path / "empty.csv").write_text("")
    with pytest.raises(DEMInputError, match=r"empty\.csv: not a readable CSV"):
        read_series(tmp_path / "empty.csv")


def test_missing_column_is_named(tmp_path):
    path = write_run(tmp_path / "heaviside.csv")
    pd.read_csv(path).drop(columns=["A_xy"]).to_csv(path, index=False)
    with pytest.raises(DEMInputError, match=r"heaviside\.csv: missing column\(s\) \['A_xy'\]"):
        read_series(path)
    # only the columns asked for must be present (compare reads six of them)
    assert list(read_series(path, columns=("t", "A_xx")).columns) == ["t", "A_xx"]


@pytest.mark.parametrize("bad", [np.nan, np.inf, "n/a"])
def test_nan_is_named_with_its_column_and_row(tmp_path, bad):
    path = write_run(tmp_path / "sinusoidal.csv")
    df = pd.read_csv(path).astype({"mu": object})
    df.loc[7, "mu"] = bad
    df.to_csv(path, index=False)
    with pytest.raises(DEMInputError, match=r"sinusoidal\.csv: column 'mu' has 1 NaN.*row 8"):
        read_series(path)
    # a column outside ``finite`` is carried as it is (calibrate checks only the columns it computes with)
    assert len(read_series(path, finite=("t", "A_xx"))) == 60


def test_too_few_samples(tmp_path):
    path = write_run(tmp_path / "heaviside.csv", n=20)
    with pytest.raises(DEMInputError, match=r"heaviside\.csv: only 20 samples, at least 50"):
        read_series(path, min_samples=50)


def test_time_must_increase_strictly(tmp_path):
    t = np.arange(1.0, 61.0)
    t[5] = t[4]
    path = write_run(tmp_path / "preshear.csv", t=t)
    with pytest.raises(DEMInputError, match=r"preshear\.csv: column 't' does not increase strictly \(data row 6\)"):
        read_series(path)


def test_a_strain_jump_is_named_with_its_rows(tmp_path):
    strain = 0.01 * np.arange(60.0)
    strain[30:] += 0.3   # 0.3 of strain from nowhere between data rows 30 and 31
    path = write_run(tmp_path / "heaviside.csv", strain=strain)
    with pytest.raises(DEMInputError, match=r"heaviside\.csv: strain jumps by \+0\.31 between data rows 30 and 31 "
                                            r"where the rate integrates to \+0\.01"):
        read_series(path)


def test_a_time_jump_without_strain_is_named(tmp_path):
    t = np.arange(1.0, 61.0)
    t[40:] += 5.0        # five time units that advance no strain at a rate of 0.01
    path = write_run(tmp_path / "preshear.csv", t=t)
    with pytest.raises(DEMInputError, match=r"preshear\.csv: strain jumps by \+0\.01 between data rows 40 and 41 "
                                            r"where the rate integrates to \+0\.06"):
        read_series(path)


def test_strain_check_tolerates_a_sampled_rate_through_zero(tmp_path):
    """A half-cosine reversal sampled in time: the trapezoid is far off in relative terms at the zero crossing."""
    t = np.linspace(0.0, 10.0, 60)
    g = 0.01 * np.cos(np.pi * t / 10.0)
    path = write_run(tmp_path / "sinusoidal.csv", t=t + 1.0, gammadot=g, strain=0.1 / np.pi * np.sin(np.pi * t / 10.0))
    assert len(read_series(path)) == 60


@pytest.mark.parametrize("cut", ["inside a field", "after a separator"])
def test_a_row_cut_off_is_named_with_its_line(tmp_path, cut):
    path = write_run(tmp_path / "heaviside.csv")
    lines = path.read_text().splitlines()
    last = lines[-1]
    lines[-1] = last[: last.index(",", len(last) // 2) + (0 if cut == "inside a field" else 1)]
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(DEMInputError, match=r"heaviside\.csv: line 61 \(data row 60\) has \d+ field\(s\), the header 17"):
        read_series(path)


def test_a_last_line_without_its_newline_is_named(tmp_path):
    path = write_run(tmp_path / "heaviside.csv")
    path.write_text(path.read_text()[:-3])   # cut inside the last field: every field is still there
    with pytest.raises(DEMInputError, match=r"heaviside\.csv: the last line \(line 61, data row 60\) does not end"):
        read_series(path)


@pytest.mark.parametrize("column, value, allowed", [
    ("A_xy", 50.0, r"\[-0\.5, 0\.5\]"), ("A_xx", -0.6, r"\[-0\.5, 0\.5\]"),
    ("p", 0.0, r"\(0, inf\]"), ("mu", -0.1, r"\[0, 2\]"), ("mu", 7.0, r"\[0, 2\]")])
def test_a_value_outside_its_physical_range_is_named_with_its_row(tmp_path, column, value, allowed):
    path = edited_run(tmp_path / "preshear.csv", column, value, row=11)
    with pytest.raises(DEMInputError, match=rf"preshear\.csv: column '{column}' = {value:g} at data row 12 is "
                                            rf"outside its physical range {allowed}"):
        read_series(path)


def test_read_series_refuses_a_mu_that_is_not_sigma_xy_over_p_naming_the_row(tmp_path):
    """mu twice |sigma_xy|/p (issue 33's factor 2) in one row: refused with the file, the column and the row."""
    path = edited_run(tmp_path / "preshear.csv", "mu", lambda mu: 2 * mu, row=11)
    with pytest.raises(DEMInputError, match=r"preshear\.csv: column 'mu' = 0\.4\d* at data row 12 but "
                                            r"\|sigma_xy\|/p = 0\.2\d* there \(1 row\(s\) in all\)"):
        read_series(path)


def test_read_series_refuses_stresses_in_pascal_with_a_hint_about_si_units(tmp_path):
    """sigma_xy and p times 1e5 (Pa at the campaigns' pressure): mu still agrees, the scale does not."""
    path = edited_run(tmp_path / "preshear.csv", ["sigma_xy", "p"], lambda v: 1e5 * v)
    with pytest.raises(DEMInputError, match=r"preshear\.csv: column 'sigma_xy' = 20000 at data row 1 is not of order "
                                            r"1 \(60 row\(s\) in all\): .* looks like SI \(Pa\): divide the "
                                            r"stresses by the imposed pressure"):
        read_series(path)


def test_sidecar_must_be_a_json_object(tmp_path):
    path = write_run(tmp_path / "heaviside.csv")
    assert read_sidecar(path) == {}
    (tmp_path / "heaviside.json").write_text("{not json")
    with pytest.raises(DEMInputError, match=r"heaviside\.json: invalid JSON sidecar"):
        read_sidecar(path)
    (tmp_path / "heaviside.json").write_text("[1, 2]")
    with pytest.raises(DEMInputError, match=r"heaviside\.json: expected a JSON object"):
        read_sidecar(path)


def test_both_stages_raise_the_contract_error():
    import calibrate
    import calibrate.io
    import compare
    assert calibrate.DEMInputError is calibrate.io.DEMInputError is compare.DEMInputError is DEMInputError
    assert issubclass(DEMInputError, ValueError)


@pytest.mark.parametrize("g", [1.0, -1.0])
def test_pre_reversal_state_averages_the_last_window_of_strain_and_signs_X_by_the_rate(g):
    from dem_contract import pre_reversal_state
    n = 200
    strain = g * np.linspace(0.0, 1.0, n)           # 1 strain in the direction g
    b = np.where(np.abs(strain) > 0.9, -0.06 * g, 0.5)  # last 0.1 strain: b = -0.06 g (the rest must not count)
    pre = pd.DataFrame({"strain": strain, "gammadot": np.full(n, 2.0 * g), "A_xx": np.where(np.abs(strain) > 0.9, 0.01, 9.0),
                        "A_xy": b, "mu": np.where(np.abs(strain) > 0.9, 0.3, 9.0)})
    st = pre_reversal_state(pre, window=0.1)
    assert st["A_xx"] == pytest.approx(0.01) and st["A_xy"] == pytest.approx(-0.06 * g) and st["mu"] == pytest.approx(0.3)
    assert st["gammadot"] == 2.0 * g and st["gammadot_sign"] == g
    assert st["X"] == pytest.approx(-0.06 * np.sqrt(2.0))   # X < 0 at steady state, whichever the direction
