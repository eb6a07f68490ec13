r"""The DEM runs as the curves route replays them: pieces of one sign of the shear rate in path strain.

Eq. 4 is rate independent (docs/model.md, Eq. 4), so a run is replayed in *path strain*:
each piece of one sign of the shear rate becomes ``model.steady_shear(length,
sign)`` at unit rate, where time equals path strain, and the model is read at
the samples' path strains (``report_grid``). The fabric starts from the run's own
DEM state before the reversal (``dem_contract.pre_reversal_state``, the start
``compare`` uses too). Runs with the same start, history and samples share one
integration (``replay_key``). The replays are integrated by ``calibrate.curves_integration``
and fitted by ``calibrate.curves_fit``.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from dem_contract import pre_reversal_state
from model import steady_shear


@dataclass
class Replay:
    """One DEM run prepared for replay: pieces (sign, path-strain length), samples and their noise."""

    label: str
    case: str
    A0: tuple
    pieces: list
    s: np.ndarray
    g: np.ndarray
    a: np.ndarray
    b: np.ndarray
    mu: np.ndarray
    sd_a: float
    sd_b: float
    _cached: dict = field(default_factory=dict, repr=False, compare=False)   # key and report grid, made once


def _noise(y):
    d = np.diff(y) / np.sqrt(2.0)
    return max(float(1.4826 * np.median(np.abs(d - np.median(d)))), 1e-6)


def prepare(cases, samples: pd.DataFrame, settings_backsolve) -> list:
    """Build a ``Replay`` for every chosen reversal run of every case.

    The history comes from the raw run (turning points of the signed strain);
    the samples are those the back-solve keeps (rate and reversal rules),
    except that no skip after a reversal is applied here.
    """
    from .smoothing import pieces as sign_pieces

    out = []
    for c in cases:
        pre = pre_reversal_state(c.preshear.data)
        for proto, run in c.runs.items():
            d = run.data
            strain = d["strain"].to_numpy()
            s_all = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(strain)))])
            idx = sign_pieces(d["gammadot"].to_numpy())
            # a turning point lies between the last sample of one sign and the first of the next
            bounds = [0.0] + [0.5 * (s_all[ix[0] - 1] + s_all[ix[0]]) for ix in idx[1:]] + [float(s_all[-1])]
            segs = [(float(np.sign(d["gammadot"].iloc[ix[0]])), bounds[k], bounds[k + 1]) for k, ix in enumerate(idx)]
            sm = samples[(samples["case"] == c.name) & (samples["protocol"] == proto)]
            keep = sm["rate_frac"].to_numpy() >= settings_backsolve.rate_min
            sm = sm[keep]
            start = run.initial_state or pre   # a schedule's later reversal starts from the state before it
            out.append(Replay(
                label=f"{c.name}/{proto}", case=c.name, A0=(start["A_xx"], start["A_xy"]),
                pieces=[(sg, e - b0) for sg, b0, e in segs if e - b0 > 0],
                s=sm["s"].to_numpy(), g=sm["g"].to_numpy(), a=sm["a_raw"].to_numpy(), b=sm["b_raw"].to_numpy(),
                mu=(sm["sigma_xy_over_p"] * sm["g"]).to_numpy(),
                sd_a=_noise(run.data["A_xx"].to_numpy()), sd_b=_noise(run.data["A_xy"].to_numpy()),
            ))
    return out


def history_of(replay: Replay):
    """The unit-rate history in path strain (time = path strain)."""
    h = None
    for sg, length in replay.pieces:
        part = steady_shear(length, sg)
        h = part if h is None else h + part
    return h


def replay_key(replay: Replay):
    """Runs with the same start, history and samples share one integration."""
    if "key" not in replay._cached:
        replay._cached["key"] = _key_of(replay)
    return replay._cached["key"]


def _key_of(replay: Replay):
    return (replay.A0, tuple(np.round([x for pc in replay.pieces for x in pc], 9)), replay.s.tobytes())


def report_grid(replay: Replay):
    """The history, the sorted report times (samples clipped to the history) and the sort order."""
    if "grid" not in replay._cached:
        h = history_of(replay)
        t = np.clip(replay.s, 0.0, h.t_end)
        order = np.argsort(t, kind="stable")
        replay._cached["grid"] = (h, t[order], order)
    return replay._cached["grid"]


def signed(m, replay: Replay):
    """Model curves ``m`` (a, b, signed friction per sample) with the friction column signed by the replay's rate."""
    out = m.copy()
    out[:, 2] *= replay.g
    return out


