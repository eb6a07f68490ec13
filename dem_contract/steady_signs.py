r"""The signs of steady shear, checked on a pre-shear's steady window (docs/data-contract.md, docs/model.md).

In steady simple shear the contract's conventions fix two signs relative to the
shear rate :math:`\dot\gamma`:

- :math:`\sigma_{xy}` has the sign of :math:`\dot\gamma` (it is > 0 when the top
  wall, moving towards +x, is dragged back: the stress resists the shear);
- :math:`A_{xy}` has the opposite sign (the fabric's state variable
  :math:`X = \sqrt2 A_{xy} \operatorname{sign}\dot\gamma` is negative at steady
  state: docs/model.md, Section 3).

Both hold in every row of every released run's steady window (data/*/,
15 + 4 runs). A sign-flipped column (another simulator's convention, a
mirrored axis) would move the calibration far from the data (flipping
sigma_xy of one run moved its X0 from 0.130 to 0.019 in issue 33), so the importer
refuses it. The window means are compared, not single rows: a small cell's
noise can flip one row's sign.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from .derived import steady_window
from .series import DEMInputError

#: column -> the sign its steady-window mean must have relative to the rate, and why.
STEADY_SIGNS = {
    "sigma_xy": (1, "the shear stress resists the shear: sigma_xy > 0 when the top wall, moving towards +x, "
                    "is dragged back (docs/data-contract.md)"),
    "A_xy": (-1, "the contacts align against the shear: X = sqrt(2) A_xy sign(gammadot) < 0 at steady state "
                 "(docs/model.md, Section 3)"),
}


def check_steady_signs(pre: pd.DataFrame, where: str) -> None:
    r"""Refuse a pre-shear whose steady window has ``sigma_xy`` or ``A_xy`` of the wrong sign.

    Over ``steady_window`` (the last half of the pre-shear's strain), with
    :math:`g` the sign of the median rate there, the means of
    :math:`g\,\sigma_{xy}` must be > 0 and of :math:`g\,A_{xy}` < 0.

    Parameters
    ----------
    pre : pandas.DataFrame
        The pre-shear's rows (``strain``, ``gammadot``, ``sigma_xy``, ``A_xy``),
        indexed as in the file they come from (row ``i`` is data row ``i + 1``).
    where : str
        The file and run, for the message (e.g. ``"seed1.csv: run heaviside of seed 1"``).

    Raises
    ------
    DEMInputError
        Naming ``where``, the column, the window's data rows, the mean and how
        many of its rows have the wrong sign.
    """
    window = steady_window(pre["strain"].to_numpy(dtype=float))
    rows = pre.index.to_numpy()[window]
    g = float(np.sign(np.median(pre["gammadot"].to_numpy(dtype=float)[window])))
    if g == 0.0:
        raise DEMInputError(f"{where}: the pre-shear's steady window (data rows {rows[0] + 1}-{rows[-1] + 1}) "
                            "does not shear (median rate 0)")
    for col, (sign, why) in STEADY_SIGNS.items():
        signed = g * pre[col].to_numpy(dtype=float)[window]
        if sign * float(np.mean(signed)) <= 0.0:
            wrong = int(np.sum(sign * signed <= 0.0))
            raise DEMInputError(
                f"{where}: column '{col}' has the wrong sign in the pre-shear's steady window (data rows "
                f"{rows[0] + 1}-{rows[-1] + 1}, rate {'> 0' if g > 0 else '< 0'}): mean sign(gammadot)*{col} = "
                f"{np.mean(signed):+.4g}, {wrong} of {len(signed)} rows of the wrong sign; expected "
                f"{'> 0' if sign > 0 else '< 0'}: {why}")


__all__ = ["STEADY_SIGNS", "check_steady_signs"]
