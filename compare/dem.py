r"""Reading the DEM time series of one case: the reversal, the fabric before it.

A case is a directory ``<label>/`` with ``preshear.csv`` and one CSV per
reversal protocol (``heaviside.csv``, ``sinusoidal.csv``), in the column layout
of the DEM contract (docs/data-contract.md), and optional JSON sidecars ``<stage>.json``. Only the
columns in ``USED_COLUMNS`` are read (and must be present); nothing beyond the
contract is needed. The contract's checks, the error type, the case labels
and every derived quantity (steady values, A0, |A|, theta_A, the reversal
check) live in ``dem_contract``; where the reversal starts and the strain
travelled since it are this package's.

Conventions
-----------
- The reversal starts where the reversal sidecar says (``reversal_t``,
  ``reversal_strain``, docs/data-contract.md; rows before it are dropped), or
  at the first sample of the reversal CSV when the sidecar lacks them.
- The initial fabric ``A0`` is the mean of ``(A_xx, A_xy)`` over the pre-shear
  samples within ``a0_window`` strain of its end (``dem_contract.pre_reversal_state``,
  the same state the calibration bounds X_c with): the DEM fabric just before
  the reversal, with its per-sample noise averaged down.
- ``steady_A`` (= |mean A|) and ``steady_mu`` (mean mu) are the steady values
  of the pre-shear (``dem_contract.steady_values``: the last half of its
  strain, the values the calibration and the campaign summary report), the
  values the reversal recovers towards (by symmetry the mirrored steady state
  has the same |A| and mu).
- The reversal run must reverse the pre-shear (``dem_contract.reversal_indices``
  on the pre-shear's rate followed by the run's).
- ``s_rev``: strain travelled since the reversal, the running sum of
  ``|d strain|`` (monotone also for a sinusoidal reversal, which first keeps
  shearing forward, stops, then turns back). It is the abscissa of every figure.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from dem_contract import (PRE_REVERSAL_WINDOW, REVERSAL_PROTOCOLS, DEMInputError, fabric_angle_deg, fabric_norm,
                          pre_reversal_state, read_series, read_sidecar, reversal_indices, split_case_label,
                          steady_values)

USED_COLUMNS = ("t", "strain", "gammadot", "A_xx", "A_xy", "mu")
A0_WINDOW = PRE_REVERSAL_WINDOW   # strain over which the pre-reversal fabric is averaged
MIN_SAMPLES = 10


@dataclass
class Reversal:
    """One DEM reversal run, ready for the model.

    Attributes
    ----------
    label, group, seed, protocol : str
        Case label, its ensemble ``p.._I..``, its seed, the reversal protocol.
    data : DataFrame
        The used columns from the reversal start on, plus ``tau`` (time since
        the reversal), ``s_rev`` (strain travelled since it), ``A_norm`` and
        ``theta_A`` (degrees, [0, 180)).
    A0 : (float, float)
        Mean (A_xx, A_xy) of the pre-shear just before the reversal.
    steady_A, steady_mu : float
        |A| and mu of the pre-shear's steady state (``dem_contract.steady_values``).
    steady_fabric : (float, float)
        Its mean (A_xx, A_xy).
    t0, strain0 : float
        Time and strain at which the reversal starts (the sidecar's
        ``reversal_t``, ``reversal_strain`` when present, else the first sample).
    rate_before : float
        Median rate at the end of the pre-shear (the rate the reversal starts from).
    """

    label: str
    group: str
    seed: str
    protocol: str
    path: Path
    data: pd.DataFrame
    A0: tuple
    steady_A: float
    steady_mu: float
    steady_fabric: tuple
    t0: float
    strain0: float
    rate_before: float = float("nan")
    meta: dict = field(default_factory=dict)


def load_reversal(case_dir, protocol: str, a0_window: float = A0_WINDOW) -> Reversal:
    """Read ``<case_dir>/preshear.csv`` and ``<case_dir>/<protocol>.csv``.

    Parameters
    ----------
    case_dir : str or Path
        ``results/dem/<label>``.
    protocol : {"heaviside", "sinusoidal"}
    a0_window : float
        Strain window at the end of the pre-shear over which A0 is averaged.

    Raises
    ------
    DEMInputError
        Bad files (see ``dem_contract.read_series``), a reversal that never shears against
        the pre-shear, or a sidecar reversal time outside the run.
    """
    case_dir = Path(case_dir)
    if protocol not in REVERSAL_PROTOCOLS:
        raise DEMInputError(f"{case_dir}: protocol {protocol!r} is not one of {REVERSAL_PROTOCOLS}")
    if not (a0_window > 0):
        raise DEMInputError(f"a0_window = {a0_window!r} must be positive")
    pre = read_series(case_dir / "preshear.csv", USED_COLUMNS, MIN_SAMPLES, what="the pre-shear of the case")
    path = case_dir / f"{protocol}.csv"
    rev = read_series(path, USED_COLUMNS, MIN_SAMPLES, what=f"the {protocol} run of the case")
    meta = read_sidecar(path)
    t_rev = s_rev0 = None
    if "reversal_t" in meta:   # docs/data-contract.md: reversal_t, reversal_strain (start of the reversal)
        t_rev = float(meta["reversal_t"])
        tol = 1e-9 * max(1.0, abs(t_rev))
        if not (pre["t"].iloc[-1] - tol <= t_rev <= rev["t"].iloc[-1]):
            raise DEMInputError(f"{path}: sidecar reversal_t = {t_rev} lies outside "
                                f"[end of pre-shear {pre['t'].iloc[-1]}, end of run {rev['t'].iloc[-1]}]")
        rev = rev[rev["t"] >= t_rev - tol].reset_index(drop=True)
        if len(rev) < MIN_SAMPLES:
            raise DEMInputError(f"{path}: fewer than {MIN_SAMPLES} samples after reversal_t = {t_rev}")
        if "reversal_strain" in meta:
            s_rev0 = float(meta["reversal_strain"])
    # the state before the reversal (dem_contract), and a check that the reversal opposes it
    st = pre_reversal_state(pre, a0_window)
    g_pre = st["gammadot"]
    if g_pre == 0.0 or reversal_indices(np.concatenate([pre["gammadot"].to_numpy(), rev["gammadot"].to_numpy()])).size == 0:
        raise DEMInputError(f"{path}: the rate never opposes the pre-shear's (median {g_pre:.4g}): no reversal")
    a0, b0 = st["A_xx"], st["A_xy"]
    steady = steady_values(pre)
    data = rev.copy()
    t0 = float(data["t"].iloc[0]) if t_rev is None else t_rev
    strain0 = float(data["strain"].iloc[0]) if s_rev0 is None else s_rev0
    data["tau"] = data["t"] - t0
    st = data["strain"].to_numpy()
    data["s_rev"] = abs(st[0] - strain0) + np.concatenate([[0.0], np.cumsum(np.abs(np.diff(st)))])
    a, b = data["A_xx"].to_numpy(), data["A_xy"].to_numpy()
    data["A_norm"], data["theta_A"] = fabric_norm(a, b), fabric_angle_deg(a, b)
    group, seed = split_case_label(case_dir.name)
    return Reversal(label=case_dir.name, group=group, seed=seed, protocol=protocol, path=path, data=data,
                    A0=(a0, b0), steady_A=steady["A_norm"], steady_mu=steady["mu"],
                    steady_fabric=(steady["A_xx"], steady["A_xy"]), t0=t0, strain0=strain0,
                    rate_before=g_pre, meta=meta)
