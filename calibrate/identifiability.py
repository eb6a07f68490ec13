r"""What the data determine: profiles, the sensitivity matrix's effective rank and the per-parameter verdict.

``identify`` is step 6b of ``pipeline.run``: the profiles of the curves fit's
objective (``profiles``), the sensitivity matrix of each model and the verdict
per parameter, from the curve fit and the bootstrap's intervals.

Sensitivity matrix
------------------
At the curve fit's optimum :math:`\hat\theta` of a model block, the columns of

.. math:: S_{ij} = \frac{\partial r_i}{\partial \theta_j}\, s_j, \qquad
          s_j = |\hat\theta_j| \ \text{(or 1 where } \hat\theta_j = 0),

are the changes of the curves fit's normalised residuals :math:`r` (``curves_fit``) per
relative change of each parameter (forward differences of relative step
``STEP``, a backward one where the forward point cannot be integrated; all
points in one ``curves_integration.curves`` batch). Its singular values
:math:`\sigma_1 \ge \dots \ge \sigma_p` give the curvature of the objective
along the right singular vectors :math:`v_k`:
:math:`C(\hat\theta + \epsilon\, v_k) - C(\hat\theta) \approx \tfrac12 \epsilon^2 \sigma_k^2`.
A unit step along :math:`v_k` (a change of 100 % in the parameters' own
scale) raises the objective by :math:`\tfrac12\sigma_k^2`; the direction is
*determined* when that exceeds the profile threshold :math:`\Delta`
(``profiles.threshold``: the data know the combination to better than 100 %),
i.e. :math:`\sigma_k \ge \sqrt{2\Delta}`. The effective rank is the number of
determined directions; relative to the largest, the threshold is
:math:`\sqrt{2\Delta}/\sigma_1`, and never below ``REL_THRESHOLD`` (1e-3,
the finite differences' own precision). The direction of :math:`\sigma_p` is
the worst-determined combination, written with the parameter names and the
components of :math:`v_p` above 0.1 in magnitude.

Verdict
-------
A parameter is *identified* when its profile interval (``profiles``) is
finite and inside its bounds; without a profile (a parameter not profiled),
when its bootstrap interval is inside its bounds and less than half of its
unit vector lies in the undetermined directions (``undetermined_weight``).
"""
from __future__ import annotations

import math
import time

import numpy as np
import pandas as pd

from model import params_from_dict

from . import curves_fit, curves_integration, fits, profiles
from .results import MODELS, Identifiability

STEP = 1e-3
REL_THRESHOLD = 1e-3
FRICTION = {"model1": "eq2", "model2": "quadratic"}
KEYS = {"model1": fits.M1_KEYS, "model2": fits.M2_KEYS}


def identify(problem, backsolve, curves, boot, log) -> Identifiability:
    """Step 6b, identifiability: profiles of X_c and the c_i, the sensitivity matrix's SVD, the verdict per parameter.

    Parameters
    ----------
    problem : calibrate.problem.Problem
        Its ``settings.profile`` says which models are profiled and how finely.
    backsolve : results.BacksolveFit
        Its document holds the friction laws the curve fit ran with.
    curves : results.CurvesFit
        The optimum profiled, and the X_c lower bound it ran under.
    boot : results.Bootstrap
        The percentile intervals: the grids' widths (``profiles.grid``) and the verdict's bootstrap interval.
    log : callable

    Returns
    -------
    results.Identifiability
        Profiles (empty with ``profile.n_points = 0``) and their intervals, SVD and verdict of both models.
    """
    settings, iv, xl = problem.settings, boot.intervals, curves.x_lower
    profs, svds, verdicts = [], [], []
    for model in MODELS:
        c0 = time.process_time()
        fitted = curves.fits[model].values
        if settings.profile.n_points > 0 and model in settings.profile.models:
            m = iv[(iv["route"] == "curves") & (iv["block"] == model)] if len(iv) else iv
            widths = dict(zip(m["parameter"], m["high"] - m["low"])) if len(m) else {}
            profs.append(profiles.profile(problem, backsolve.doc, model, fitted, x_lower=xl, widths=widths))
            log(f"profiles {model}: {profiles.PROFILED[model]} x {settings.profile.n_points} points, "
                f"{time.process_time() - c0:.1f} s CPU")
        S, _, r0 = sensitivity(problem.replays, backsolve.doc, model, fitted, problem.sigma_mu, settings.curves)
        delta = profiles.threshold(r0, 0.5 * float(np.sum(r0**2)), S.shape[1], settings.profile.level)
        svds.append(svd_table(S, KEYS[model], model, delta))
    prof = pd.concat(profs, ignore_index=True) if profs else pd.DataFrame(columns=profiles.COLUMNS)
    prof_iv = profiles.intervals(prof, xl) if len(prof) else pd.DataFrame(
        columns=["model", "parameter", "low", "high", "identified", "note"])
    for model, svd in zip(MODELS, svds):
        m = iv[(iv["route"] == "curves") & (iv["block"] == model)] if len(iv) else iv
        boot_iv = {r["parameter"]: (r["low"], r["high"]) for _, r in m.iterrows()}
        bounds = {k: profiles.bounds_of(model, k, xl) for k in KEYS[model]}
        verdicts.append(verdict(model, curves.fits[model].values, boot_iv, prof_iv[prof_iv["model"] == model], svd,
                                bounds))
    return Identifiability(prof, prof_iv, pd.concat(svds, ignore_index=True), pd.concat(verdicts, ignore_index=True))


def sensitivity(replays, base_doc: dict, model: str, fitted: dict, sigma_mu: float,
                settings: curves_integration.CurvesSettings) -> tuple:
    """The scaled sensitivity matrix :math:`S` of the module Notes and the column scales.

    Returns
    -------
    S : ndarray, shape (n_residuals, n_parameters)
        Columns in ``KEYS[model]`` order; a column whose both difference points
        fail is NaN.
    scales : ndarray
    r0 : ndarray
        The residuals at the optimum.
    """
    keys = KEYS[model]
    x0 = np.array([fitted[k] for k in keys], float)
    scales = np.where(x0 != 0, np.abs(x0), 1.0)
    points = [x0]
    for j in range(len(keys)):
        for sign in (1.0, -1.0):
            x = x0.copy()
            x[j] += sign * STEP * scales[j]
            points.append(x)
    items = []
    for x in points:
        try:
            items.append((params_from_dict({**base_doc, model: dict(zip(keys, x.tolist()))}), model, FRICTION[model]))
        except ValueError:
            items.append(None)
    got = curves_integration.curves([it for it in items if it is not None], replays, settings)
    it = iter(got)
    vecs = []
    for item in items:
        c = next(it) if item is not None else ValueError("out of range")
        vecs.append(None if isinstance(c, Exception) else curves_fit.residual_vector(c, replays, sigma_mu, settings))
    if vecs[0] is None:
        raise ValueError(f"identifiability: the {model} optimum cannot be integrated on the calibration runs")
    S = np.full((vecs[0].size, len(keys)), np.nan)
    for j in range(len(keys)):
        fwd, bwd = vecs[1 + 2 * j], vecs[2 + 2 * j]
        if fwd is not None:
            S[:, j] = (fwd - vecs[0]) / STEP
        elif bwd is not None:
            S[:, j] = (vecs[0] - bwd) / STEP
    return S, scales, vecs[0]


def svd_table(S: np.ndarray, keys, model: str, delta: float = 0.0) -> pd.DataFrame:
    r"""Singular values of ``S`` (NaN columns dropped), relative to the largest, and each right singular vector.

    ``delta`` is the profile threshold :math:`\Delta` (module Notes); the relative threshold is
    ``max(sqrt(2 delta) / sigma_1, REL_THRESHOLD)``.

    Returns
    -------
    DataFrame
        One row per singular value: ``model``, ``k``, ``singular_value``,
        ``relative``, ``above_threshold``, ``effective_rank`` (same on every
        row), ``threshold``, ``direction`` (the vector in parameter names) and
        one ``v_<name>`` column per parameter.
    """
    ok = np.all(np.isfinite(S), axis=0)
    names = [k for k, o in zip(keys, ok) if o]
    _, sv, vt = np.linalg.svd(S[:, ok], full_matrices=False)
    rel = sv / sv[0] if sv[0] > 0 else np.zeros_like(sv)
    threshold = max(float(np.sqrt(2.0 * delta) / sv[0]) if sv[0] > 0 else 1.0, REL_THRESHOLD)
    rank = int(np.sum(rel >= threshold))
    rows = []
    for k, (s, r, v) in enumerate(zip(sv, rel, vt)):
        v = v * np.sign(v[np.argmax(np.abs(v))])
        rows.append({"model": model, "k": k + 1, "singular_value": s, "relative": r, "above_threshold": r >= threshold,
                     "effective_rank": rank, "n_parameters": len(keys), "threshold": threshold,
                     "direction": direction(v, names),
                     **{f"v_{n}": float(x) for n, x in zip(names, v)}})
    return pd.DataFrame(rows)


def direction(v, names, floor: float = 0.1) -> str:
    """A singular vector in parameter names: ``+0.71 c1 -0.70 X_c`` (components above ``floor``)."""
    order = np.argsort(-np.abs(v))
    return " ".join(f"{v[i]:+.2f} {names[i]}" for i in order if abs(v[i]) >= floor)


def undetermined_weight(svd: pd.DataFrame, name: str) -> float:
    r"""Length of a parameter's unit vector projected on the undetermined directions: :math:`\sqrt{\sum_k v_{kj}^2}`
    over the :math:`v_k` below the threshold (0: every direction it enters is determined; 1: none is)."""
    col = f"v_{name}"
    if col not in svd.columns:
        return math.nan
    low = svd[~svd["above_threshold"].astype(bool)]
    return float(np.sqrt(np.sum(low[col].to_numpy(float) ** 2)))


def verdict(model: str, fitted: dict, boot: dict, prof: pd.DataFrame, svd: pd.DataFrame, bounds: dict) -> pd.DataFrame:
    """One row per parameter of the block: estimate, intervals, identified yes/no and why.

    A profiled parameter is identified when its profile interval is finite and
    inside its bounds (``profiles.interval``); a parameter not profiled, when its
    bootstrap interval lies inside its bounds and less than half of its unit
    vector lies in the undetermined directions (``undetermined_weight`` < 0.5).

    Parameters
    ----------
    fitted : dict
        The curve fit's values.
    boot : dict
        name -> (low, high): the bootstrap interval.
    prof : DataFrame
        ``profiles.intervals`` rows of this model (may be empty).
    svd : DataFrame
        ``svd_table`` of this model.
    bounds : dict
        name -> (low, high): the search bounds.
    """
    worst = svd.iloc[-1]
    rows = []
    for name, value in fitted.items():
        b_lo, b_hi = boot.get(name, (math.nan, math.nan))
        p = prof[prof["parameter"] == name] if len(prof) else prof
        lo, hi = bounds.get(name, (-math.inf, math.inf))
        weight = undetermined_weight(svd, name)
        notes = []
        if len(p):
            p = p.iloc[0]
            p_lo, p_hi = float(p["low"]), float(p["high"])
            ident = bool(p["identified"])
            notes.append("profile: " + ("finite, inside the bounds" if ident else p["note"]))
        else:
            p_lo = p_hi = math.nan
            inside = bool(np.isfinite(b_lo) and np.isfinite(b_hi) and lo < b_lo and b_hi < hi)
            ident = inside and not weight >= 0.5
            notes.append("not profiled: bootstrap interval " + ("inside" if inside else "not inside") + " the bounds")
        if weight >= 0.5:
            notes.append(f"{weight:.2f} of it lies in the undetermined directions (the worst: {worst['direction']}, "
                         f"relative singular value {worst['relative']:.2g} below {worst['threshold']:.2g})")
        rows.append({"model": model, "parameter": name, "estimate": value, "bootstrap_low": b_lo,
                     "bootstrap_high": b_hi, "profile_low": p_lo, "profile_high": p_hi,
                     "identified": "yes" if ident else "no", "undetermined_weight": weight, "note": "; ".join(notes)})
    return pd.DataFrame(rows)
