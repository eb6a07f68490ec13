"""Read back a table the pipeline wrote (predictions, errors, parameter tables), refusing a cut or ragged one.

pandas reads a row cut off in the middle (a killed job, a full disk) as a row
whose missing fields are NaN, or whose last number is shortened, and goes on;
every stage that reads another stage's CSV goes through ``read_table``, which
refuses such a file by name and line instead. The DEM series have their own
reader (``dem_contract.series.read_series``), which adds the contract's checks.
"""
from __future__ import annotations

import csv
import io
from pathlib import Path

import pandas as pd

from .series import DEMInputError


def check_complete_rows(path, text: str | None = None) -> int:
    """Every record of a CSV holds as many fields as its header, and the file ends with a newline.

    Records are parsed by the ``csv`` module (quoted fields may hold commas and
    line breaks), so a line is named as the reader counts it.

    Parameters
    ----------
    path : str or Path
    text : str, optional
        The file's text, if already read.

    Returns
    -------
    int
        The number of data records (after the header).

    Raises
    ------
    DEMInputError
        Naming the file and the line (and data row) with too few or too many
        fields, or the last line when it lacks its newline (a row cut off while
        being written).
    """
    path = Path(path)
    if text is None:
        try:
            text = path.read_text()
        except (OSError, UnicodeDecodeError) as exc:
            raise DEMInputError(f"{path}: not a readable CSV ({exc})") from None
    if not text.strip():
        raise DEMInputError(f"{path}: empty file (no header)")
    reader = csv.reader(io.StringIO(text, newline=""))
    try:
        header = next(reader)
        n_rows = 0
        for record in reader:
            if not record:  # a blank line: pandas skips it too
                continue
            n_rows += 1
            if len(record) != len(header):
                raise DEMInputError(f"{path}: line {reader.line_num} (data row {n_rows}) has {len(record)} "
                                    f"field(s), the header {len(header)}: a ragged row (cut off while being "
                                    "written?)")
    except csv.Error as exc:
        raise DEMInputError(f"{path}: line {reader.line_num}: not a readable CSV ({exc})") from None
    if not text.endswith("\n"):
        raise DEMInputError(f"{path}: the last line (line {reader.line_num}, data row {n_rows}) does not end with "
                            "a newline: the row was cut off while being written")
    return n_rows


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
