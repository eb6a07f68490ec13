r"""Model 1 and Model 2 integrated on a DEM run's own imposed history.

The imposed history is the run's measured ``gammadot`` (walls over gap), cleaned
after the reversal's kind (``Reversal.kind``, from its sidecar: a schedule's
step is cleaned as a Heaviside run, its half cosine as a sinusoidal one, in
either direction) and integrated with ``model.tabulated``:

- Heaviside: the walls switch in one step and then keep their speed, so the rate
  after the switch is one constant, taken as the median of the measured rate.
  The whole run is sheared at that constant from the reversal on: the jump
  stays sharp (it is at the first sample) and the gap's fluctuations are not
  read as changes of the imposed rate. The model is reported at the times at
  which its strain equals the DEM strain of each sample (the model is rate
  independent, so this compares at equal strain exactly).
- Sinusoidal: the measured rate as tabulated (piecewise linear between samples).
  If noise makes it change sign more than once, it is smoothed with a centred
  running mean of the narrowest odd width (3, 5, 9, ...) that leaves a single
  sign change; the width used is recorded (1 = raw). The model is reported at
  the DEM sample times; the largest gap between the model's and the DEM's
  strain is recorded (``strain_mismatch``).

Both models start from the DEM fabric ``A0`` just before the reversal. Model 1
may raise ``PoleError`` for poor parameters: it is caught and returned as a
status, never raised.

``predict`` integrates one model with ``model.simulate`` (LSODA); ``predict_many``
integrates many parameter sets on the same run in one ``model.batched.simulate_batch``
call (per-trajectory Dormand-Prince 5(4); a trajectory that meets the pole, turns
stiff or runs out of steps falls back to ``simulate`` alone), equal to ``predict`` to
the batched-vs-LSODA agreement (better than 1e-6 in |A|, theta_A and mu).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from dem_contract import reversal_indices
from model import PoleError, simulate, tabulated
from model.batched import simulate_batch

from .dem import Reversal

MODELS = ("model1", "model2")
DEFAULT_FRICTION = {"model1": "eq2", "model2": "quadratic"}   # each model with its own friction law
MAX_SMOOTHING = 201


@dataclass
class Prediction:
    """A model's curve on a DEM run's sample grid.

    ``table`` has the DEM's ``s_rev`` and ``strain`` and the model's ``A_xx,
    A_xy, A_norm, theta_A, mu`` (one row per DEM sample), or is None when the
    integration failed; ``status`` is ``"ok"`` or names the failure.
    """

    label: str
    protocol: str
    model: str
    friction: str
    table: pd.DataFrame | None
    status: str
    rate_smoothing: int
    strain_mismatch: float


def _sign_changes(g):
    """Every change of sign of ``g`` (zeros skipped): ``dem_contract.reversal_indices`` with no dead band or minimum run."""
    return int(reversal_indices(g, dead_band=0.0, min_run=1).size)


def clean_rate(rev: Reversal):
    """The imposed rate of a reversal run, cleaned as the module docstring says.

    Returns
    -------
    gammadot : ndarray
        Cleaned rate at the DEM samples.
    width : int
        Width of the running mean used (1: none; 0: replaced by a constant).
    """
    g = rev.data["gammadot"].to_numpy(dtype=float)
    if rev.kind == "heaviside":
        after = g[g * np.median(g) > 0]
        return np.full_like(g, float(np.median(after))), 0
    width = 1
    gs = g
    while _sign_changes(gs) > 1:
        width = 3 if width == 1 else 2 * width - 1
        if width > MAX_SMOOTHING:
            raise ValueError(f"{rev.path}: the measured gammadot changes sign {_sign_changes(g)} times and "
                             f"a running mean over {MAX_SMOOTHING} samples does not leave a single reversal")
        pad = width // 2
        padded = np.concatenate([np.full(pad, g[0]), g, np.full(pad, g[-1])])
        gs = np.convolve(padded, np.ones(width) / width, mode="valid")
    return gs, width


def imposed_history(rev: Reversal):
    """History, report times and cleaning width for a reversal run.

    Returns
    -------
    history : model.History
    t_eval : ndarray
        Model times at which to report, one per DEM sample.
    width : int
    """
    tau = rev.data["tau"].to_numpy(dtype=float)
    g, width = clean_rate(rev)
    if rev.kind == "heaviside":
        ds = rev.data["strain"].to_numpy(dtype=float) - rev.strain0
        t_eval = np.maximum.accumulate(np.clip(ds / g[0], 0.0, None))   # equal strain, monotone
        history = tabulated(np.array([0.0, max(tau[-1], t_eval[-1])]), np.array([g[0], g[0]]))
    else:
        if tau[0] > 0:   # the first sample comes after the reversal start: begin at the pre-shear's rate
            tau, g = np.concatenate([[0.0], tau]), np.concatenate([[rev.rate_before], g])
            history = tabulated(tau, g)
            t_eval = tau[1:]
        else:
            history = tabulated(tau, g)
            t_eval = tau
    return history, t_eval, width


def predict(rev: Reversal, params, model: str, friction: str | None = None) -> Prediction:
    """Integrate ``model`` from the DEM's ``A0`` on the run's imposed history.

    Parameters
    ----------
    rev : Reversal
    params : ModelParams, dict or path
    model : {"model1", "model2"}
    friction : {"eq2", "quadratic"}, optional
        Default ``DEFAULT_FRICTION[model]``: Eq. 2 for Model 1, the quadratic
        law of [15] for Model 2.
    """
    if model not in MODELS:
        raise ValueError(f"model = {model!r} is not one of {MODELS}")
    friction = friction or DEFAULT_FRICTION[model]
    history, t_eval, width = imposed_history(rev)
    try:
        sim = simulate(params, history, model=model, A0=rev.A0, friction=friction, t_eval=t_eval)
    except (ValueError, FloatingPointError) as exc:   # PoleError; e.g. no steady state, non-finite output
        return _prediction(rev, model, friction, width, exc)
    return _prediction(rev, model, friction, width, sim)


def predict_many(rev: Reversal, params_list, model: str, friction: str | None = None) -> list:
    """``predict`` for each parameter set of ``params_list`` on the same run, in one batched integration.

    Parameters
    ----------
    rev : Reversal
    params_list : sequence of ModelParams, dict or path
    model : {"model1", "model2"}
    friction : {"eq2", "quadratic"}, optional

    Returns
    -------
    list of Prediction
        One per parameter set, in order; a failed trajectory has ``table`` None and the status
        ``predict`` gives (its error is ``simulate``'s: the batch hands such trajectories over).
    """
    if model not in MODELS:
        raise ValueError(f"model = {model!r} is not one of {MODELS}")
    friction = friction or DEFAULT_FRICTION[model]
    params_list = list(params_list)
    if not params_list:
        return []
    history, t_eval, width = imposed_history(rev)
    res = simulate_batch(params_list, history, model=model, A0=tuple(rev.A0), friction=friction, t_eval=t_eval)
    out = []
    for i, err in enumerate(res.errors):
        if err is not None and not isinstance(err, (ValueError, FloatingPointError)):
            raise err                                   # what predict would raise (e.g. a step budget)
        out.append(_prediction(rev, model, friction, width, err if err is not None else res.trajectory(i)))
    return out


def predict_loop(rev: Reversal, params_list, model: str, friction: str | None = None) -> list:
    """``predict_many`` one ``predict`` (``model.simulate``, LSODA) at a time: the reference it is checked against."""
    return [predict(rev, p, model, friction) for p in params_list]


INTEGRATORS = {"batched": predict_many, "loop": predict_loop}


def _prediction(rev: Reversal, model: str, friction: str, width: int, sim) -> Prediction:
    """A ``Prediction`` from ``simulate``'s table, or from the error it raised (then ``table`` is None)."""
    if isinstance(sim, PoleError):
        return Prediction(rev.label, rev.protocol, model, friction, None,
                          f"PoleError: {sim}".replace("\n", " "), width, np.nan)
    if isinstance(sim, Exception):
        return Prediction(rev.label, rev.protocol, model, friction, None,
                          f"{type(sim).__name__}: {sim}".replace("\n", " "), width, np.nan)
    ds_model = sim["strain"].to_numpy()
    ds_dem = rev.data["strain"].to_numpy() - rev.strain0
    table = pd.DataFrame({
        "s_rev": rev.data["s_rev"].to_numpy(),
        "strain": rev.data["strain"].to_numpy(),
        "A_xx": sim["A_xx"].to_numpy(), "A_xy": sim["A_xy"].to_numpy(),
        "A_norm": sim["A_norm"].to_numpy(), "theta_A": sim["theta_A"].to_numpy(),
        "mu": sim["mu"].to_numpy(),
    })
    return Prediction(rev.label, rev.protocol, model, friction, table, "ok", width,
                      float(np.max(np.abs(ds_model - ds_dem))))
