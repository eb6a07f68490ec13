"""Read back a table the pipeline wrote (predictions, errors, parameter tables), refusing a cut or ragged one.

pandas reads a row cut off in the middle (a killed job, a full disk) as a row
whose missing fields are NaN, or whose last number is shortened, and goes on;
every stage that reads another stage's CSV goes through ``read_table``, which
refuses such a file by name and line instead. The DEM series have their own
reader (``dem_contract.series.read_series``), which adds the contract's checks.
"""
from __future__ import annotations

import io
from pathlib import Path

import pandas as pd

from .series import DEMInputError, check_complete_rows


def read_table(path, columns=(), what: str = "a table") -> pd.DataFrame:
    """Read a CSV one stage wrote for another, refusing a truncated or ragged one.

    Parameters
    ----------
    path : str or Path
    columns : sequence of str
        Columns that must be present (others are kept).
    what : str
        What the file should be (e.g. ``"the comparison's curves"``), named in
        the messages.

    Returns
    -------
    pandas.DataFrame

    Raises
    ------
    DEMInputError
        In the order checked: the file is missing; a ragged or cut row
        (``check_complete_rows``); pandas cannot parse it (``on_bad_lines="error"``)
        or reads another number of rows than the file holds; a column is missing.
        Every message names the file.
    """
    path = Path(path)
    if not path.is_file():
        raise DEMInputError(f"{path}: {what} not found")
    try:
        text = path.read_text()
    except (OSError, UnicodeDecodeError) as exc:
        raise DEMInputError(f"{path}: not a readable CSV ({exc})") from None
    n_rows = check_complete_rows(path, text)
    try:
        df = pd.read_csv(io.StringIO(text), on_bad_lines="error")
    except (pd.errors.ParserError, pd.errors.EmptyDataError, ValueError) as exc:
        raise DEMInputError(f"{path}: not a readable CSV ({str(exc).strip().splitlines()[0]})") from None
    if len(df) != n_rows:
        raise DEMInputError(f"{path}: pandas read {len(df)} row(s) of the {n_rows} the file holds ({what})")
    missing = [c for c in columns if c not in df.columns]
    if missing:
        raise DEMInputError(f"{path}: column(s) {', '.join(missing)} missing ({what}; expected {', '.join(columns)})")
    return df
