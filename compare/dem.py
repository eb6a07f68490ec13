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
  at the first sample of the reversal CSV when the sidecar lacks them. A
  reversal schedule's run holds several reversals (the sidecar's
  ``reversals``): ``load_reversals`` splits it into one ``Reversal`` per
  reversal (``dem_contract.split_transients``), each from its reversal to the
  next, started from the state just before it.
- The initial fabric ``A0`` is ``(A_xx, A_xy)`` at the reversal, estimated over
  the samples within ``a0_window`` strain of the end of the leg before it
  (``dem_contract.pre_reversal_state``, the same state the calibration bounds X_c
  with): the mean of the steady pre-shear, or, before a schedule's later reversal,
  a straight line fitted to the moving transient and taken at its end (no lag).
- ``steady_A`` (= |mean A|) and ``steady_mu`` (mean mu) are the steady values
  of the pre-shear (``dem_contract.steady_values``: the last half of its
  strain, the values the calibration and the campaign summary report), the
  values the reversal recovers towards (by symmetry the mirrored steady state
  has the same |A| and mu).
- Each reversal has a kind (a Heaviside step or a half cosine) and a direction
  (-1 against the pre-shear, +1 back along it) from its sidecar, or from the
  protocol's name for the classic runs (``dem_contract.derived.reversal_kinds``);
  ``canonical`` reflects a +1 reversal (x -> -x) into the frame of the -1 ones.
- The reversal run must reverse the pre-shear (``dem_contract.reversal_indices``
  on the pre-shear's rate followed by the run's).
- ``s_rev``: strain travelled since the reversal, the running sum of
  ``|d strain|`` (monotone also for a sinusoidal reversal, which first keeps
  shearing forward, stops, then turns back). It is the abscissa of every figure.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from dem_contract import (PRE_REVERSAL_WINDOW, REVERSAL_PROTOCOLS, DEMInputError, fabric_angle_deg, fabric_norm,
                          read_series, read_sidecar, split_case_label, split_transients, steady_values)
from dem_contract.derived import mirror_reversal, reversal_kinds

#: A reversal protocol's name: heaviside, sinusoidal or a schedule's (docs/scene.md).
PROTOCOL_NAME = re.compile(r"^[a-z][a-z0-9_]*$")

USED_COLUMNS = ("t", "strain", "gammadot", "A_xx", "A_xy", "mu")
A0_WINDOW = PRE_REVERSAL_WINDOW   # strain over which the fabric at the reversal is estimated
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
        Median rate at the end of the leg before the reversal (the rate it starts from).
    kind : {"heaviside", "sinusoidal"}
        A step of the rate or a half-cosine transition (``dem_contract.derived.reversal_kinds``):
        it, not the protocol's name, sets the imposed history (``predict``) and the figure.
    direction : int
        -1: against the pre-shear; +1: back along it (a schedule's return), the mirror image
        of a -1 reversal (``dem_contract.derived.mirror_reversal``).
    transition_strain : float or None
        The half cosine's strain (None for a step, or when the sidecar does not say).
    reversal : int
        The reversal's number in its run, from 1.
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
    kind: str = "heaviside"
    direction: int = -1
    transition_strain: float | None = None
    reversal: int = 1


def load_reversal(case_dir, protocol: str, a0_window: float = A0_WINDOW) -> Reversal:
    """Read ``<case_dir>/preshear.csv`` and ``<case_dir>/<protocol>.csv``: its first reversal.

    Parameters
    ----------
    case_dir : str or Path
        ``results/dem/<label>``.
    protocol : str
        ``heaviside``, ``sinusoidal`` or a reversal schedule's name (``load_reversals``
        gives each of a schedule's reversals).
    a0_window : float
        Strain window at the end of the pre-shear over which A0 is averaged.

    Raises
    ------
    DEMInputError
        Bad files (see ``dem_contract.read_series``), a reversal that never shears against
        the pre-shear, or a sidecar reversal time outside the run.
    """
    return load_reversals(case_dir, protocol, a0_window)[0]


def load_reversals(case_dir, protocol: str, a0_window: float = A0_WINDOW) -> list:
    """Every reversal of ``<case_dir>/<protocol>.csv``, one ``Reversal`` each (``dem_contract.split_transients``).

    A heaviside or sinusoidal run gives one; a reversal schedule one per reversal, each
    from its own reversal to the next, started from the state just before it
    (``A0``, ``rate_before``) and labelled with its number (``meta["reversal"]``).
    """
    case_dir = Path(case_dir)
    if not isinstance(protocol, str) or not PROTOCOL_NAME.match(protocol) or protocol == "preshear":
        raise DEMInputError(f"{case_dir}: protocol {protocol!r} is not a reversal protocol "
                            f"({', '.join(REVERSAL_PROTOCOLS)} or a schedule's name)")
    if not (a0_window > 0):
        raise DEMInputError(f"a0_window = {a0_window!r} must be positive")
    pre = read_series(case_dir / "preshear.csv", USED_COLUMNS, MIN_SAMPLES, what="the pre-shear of the case")
    path = case_dir / f"{protocol}.csv"
    rev = read_series(path, USED_COLUMNS, MIN_SAMPLES, what=f"the {protocol} run of the case")
    meta = read_sidecar(path)
    transients = split_transients(pre, rev, meta, a0_window, what=str(path), min_samples=MIN_SAMPLES)
    kinds = reversal_kinds(meta, protocol, what=str(path))
    if len(kinds) != len(transients):
        raise DEMInputError(f"{path}: the sidecar's schedule makes {len(kinds)} reversal(s), the run holds "
                            f"{len(transients)}")
    pre_sign = transients[0].initial["gammadot_sign"]   # the pre-shear's direction (the leg before reversal 1)
    steady = steady_values(pre)
    group, seed = split_case_label(case_dir.name)
    out = []
    for tr, kind in zip(transients, kinds):
        g_pre = tr.initial["gammadot"]
        if g_pre == 0.0:
            raise DEMInputError(f"{path}: the rate before reversal {tr.index} does not move (median {g_pre:.4g})")
        if tr.sign != kind["direction"] * pre_sign:
            raise DEMInputError(f"{path}: reversal {tr.index} shears with sign {tr.sign:+.0f}, its sidecar's direction "
                                f"{kind['direction']:+d} relative to the pre-shear (sign {pre_sign:+.0f}) says "
                                f"{kind['direction'] * pre_sign:+.0f}")
        data = tr.data.copy()
        data["tau"] = data["t"] - tr.t0
        st = data["strain"].to_numpy()
        data["s_rev"] = abs(st[0] - tr.strain0) + np.concatenate([[0.0], np.cumsum(np.abs(np.diff(st)))])
        a, b = data["A_xx"].to_numpy(), data["A_xy"].to_numpy()
        data["A_norm"], data["theta_A"] = fabric_norm(a, b), fabric_angle_deg(a, b)
        out.append(Reversal(label=case_dir.name, group=group, seed=seed, protocol=protocol, path=path, data=data,
                            A0=(tr.initial["A_xx"], tr.initial["A_xy"]), steady_A=steady["A_norm"],
                            steady_mu=steady["mu"], steady_fabric=(steady["A_xx"], steady["A_xy"]), t0=tr.t0,
                            strain0=tr.strain0, rate_before=g_pre,
                            meta=meta if tr.n_reversals == 1 else dict(meta, reversal=tr.index),
                            kind=kind["kind"], direction=kind["direction"],
                            transition_strain=kind["transition_strain"], reversal=tr.index))
    return out


_DATA = object()   # canonical's default: the reversal's own data


def canonical(rev: Reversal, table=_DATA) -> pd.DataFrame | None:
    """``rev``'s data (or a model's ``table`` on its samples) in the frame of the -1 reversals.

    A +1 reversal (back along the pre-shear) is reflected x -> -x
    (``dem_contract.derived.mirror_reversal``: A_xy, theta_A, strain, rate and shear stress
    change sign or turn to 180 - theta_A; |A|, mu and ``s_rev`` do not); a -1 one is
    returned as it is (the same object). A failed model's table (None) stays None.
    """
    t = rev.data if table is _DATA else table
    return mirror_reversal(t) if (t is not None and rev.direction > 0) else t
