r"""How far the predictions move when one fitted parameter moves.

The paper warns that Model 1 is very sensitive to its coefficients. For one
representative DEM run per protocol (the first seed of the first ensemble), each
coefficient of the model's evolution law (Model 1: a1, b1, c1, a2, b2, c2, X_c;
Model 2: c1, c2, c3) is moved alone:

- by -f and +f relatively for each f in ``fractions`` (default 1 % and 5 %);
- to each end of its bootstrap interval (``intervals`` of params.yaml), when the
  calibration gave one.

Each perturbed model is integrated as in ``predict`` (from the run's fabric, on
its own history): the fitted and all perturbed parameter sets of one model and
run in one batched integration (``predict.predict_many``, equal to ``predict``'s
LSODA to better than 1e-6 in |A|, theta_A and mu). The table records the largest change from the
fitted-parameter curve of |A|, theta_A (modulo 180) and mu, the RMSE against the
DEM, and which axis theta_A turns through; a perturbation that leaves the
allowed range or makes Model 1 hit its pole is a row with that status. With
the default fractions this is 6 integrations per coefficient: 60 per protocol.
The friction-law parameters are not perturbed (they scale mu, not the fabric).
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from dem_contract import angle_difference, split_case_label
from dem_contract.passage import passage
from model import load_params, params_from_dict

from . import metrics
from .comparison import case_dirs_with
from .dem import load_reversal
from .figures import sensitivity_figure
from .metrics import QUANTITIES
from .predict import DEFAULT_FRICTION, INTEGRATORS, MODELS

KEYS = {"model1": ("a1", "b1", "c1", "a2", "b2", "c2", "X_c"), "model2": ("c1", "c2", "c3")}


def perturbations(params, model, fractions=(0.01, 0.05)):
    """List of (key, kind, envelope, value) for one model's coefficients.

    ``kind`` is e.g. ``"+5%"`` or ``"interval low"``; ``envelope`` groups runs
    for the band (``"1%"``, ``"5%"``, ``"interval"``).
    """
    block = params.to_dict()[model]
    intervals = (params.intervals or {}).get(model, {})
    out = []
    for key in KEYS[model]:
        v = block[key]
        for f in fractions:
            for sign in (-1, 1):
                out.append((key, f"{'+' if sign > 0 else '-'}{100 * f:g}%", f"{100 * f:g}%", v * (1 + sign * f)))
        if key in intervals:
            lo, hi = (float(x) for x in intervals[key])
            out.append((key, "interval low", "interval", lo))
            out.append((key, "interval high", "interval", hi))
    return out


def _representative(case_dirs):
    by_group = {}
    for d in case_dirs:
        name = str(d).rstrip("/").split("/")[-1]
        by_group.setdefault(split_case_label(name)[0], []).append((name, d))
    first = sorted(by_group)[0]
    return sorted(by_group[first])[0][1]


def run(case_dirs, params_path, protocols, figure_path, set_name="all", fractions=(0.01, 0.05), friction=None,
        integrator="batched"):
    """Perturb, integrate, tabulate and plot; returns (table, number of integrations).

    ``integrator``: ``"batched"`` (``predict.predict_many``) or ``"loop"`` (``predict.predict_loop``,
    one LSODA integration at a time).
    """
    if integrator not in INTEGRATORS:
        raise ValueError(f"integrator = {integrator!r} is not one of {', '.join(INTEGRATORS)}")
    integrate = INTEGRATORS[integrator]
    params = load_params(params_path)
    friction = dict(DEFAULT_FRICTION, **(friction or {}))
    rows, bands, n = [], {}, 0
    for protocol in protocols:
        rev = load_reversal(_representative(case_dirs_with(case_dirs, protocol)), protocol)  # cases may lack a protocol
        dem = rev.data
        for model in MODELS:
            base = dict(set=set_name, case=rev.label, protocol=protocol, model=model)
            nominal, perturbed, curves, n_runs = _perturbed_rows(base, rev, params, params_path, model,
                                                                 friction[model], fractions, integrate)
            rows.append(_nominal_row(base, nominal, dem))
            rows += perturbed
            n += n_runs
            bands[(protocol, model)] = dict(s_rev=dem["s_rev"].to_numpy(), dem=dem, case=rev.label,
                                            nominal=nominal.table, envelopes=_envelopes(curves, nominal))
    sensitivity_figure(bands, figure_path)
    return pd.DataFrame(rows), n


def _nominal_row(base, nominal, dem):
    """The row of the fitted parameters: status, theta_A's passage and RMSE against the DEM."""
    if nominal.table is None:
        return dict(base, parameter="(fitted)", kind="nominal", status=nominal.status)
    return dict(base, parameter="(fitted)", kind="nominal", status="ok",
                theta_passage=_passage(nominal.table),
                **{f"rmse_{q}": metrics.errors(dem, nominal.table)[f"rmse_{q}"] for q in QUANTITIES})


def _perturbed_rows(base, rev, params, params_path, model, friction, fractions, integrate):
    """The fitted curve and one row per perturbation of ``model``'s coefficients (see ``perturbations``).

    The fitted and every valid perturbed parameter set are integrated together
    (``integrate``: ``predict.predict_many``, or ``predict.predict_loop``). Returns the fitted ``Prediction``, the rows, the
    perturbed curves per envelope (None for an invalid parameter set or a
    failed run) and the number of integrations.
    """
    cases = []          # (row, envelope, parameters or the invalid/skipped status)
    for key, kind, env, value in perturbations(params, model, fractions):
        row = dict(base, parameter=key, kind=kind, fitted=params.to_dict()[model][key], value=value)
        if value == row["fitted"] and env != "interval":
            cases.append((row, None, "skipped: fitted value is 0, a relative change is no change"))
            continue
        d = params.to_dict()
        d[model][key] = float(value)
        try:
            cases.append((row, env, params_from_dict(d, source=f"{params_path} with {model}.{key} = {value:.6g}")))
        except ValueError as exc:
            cases.append((row, env, f"invalid: {exc}"))
    valid = [p for _, _, p in cases if not isinstance(p, str)]
    nominal, *preds = integrate(rev, [params, *valid], model, friction)
    preds = iter(preds)
    rows, curves = [], {}
    for row, env, p in cases:
        if isinstance(p, str):
            rows.append(dict(row, status=p))
            if env is not None:
                curves.setdefault(env, []).append(None)
            continue
        pred = next(preds)
        curves.setdefault(env, []).append(pred.table)
        if pred.table is None:
            rows.append(dict(row, status=pred.status))
            continue
        rows.append(_change_row(row, pred.table, nominal.table, rev.data))
    return nominal, rows, curves, 1 + len(valid)


def _change_row(row, table, nominal_table, dem):
    """``row`` with status ok, the largest change from the fitted curve, the RMSE against the DEM and theta's passage."""
    row["status"] = "ok"
    if nominal_table is not None:
        for q in QUANTITIES:
            diff = table[q].to_numpy() - nominal_table[q].to_numpy()
            if q == "theta_A":
                diff = angle_difference(table[q], nominal_table[q])
            row[f"dmax_{q}"] = float(np.max(np.abs(diff)))
    row.update({f"rmse_{q}": v for q, v in ((q, metrics.errors(dem, table)[f"rmse_{q}"]) for q in QUANTITIES)})
    row["theta_passage"] = _passage(table)
    return row


def _passage(table) -> str:
    """Which axis a model curve's theta_A turns through (``dem_contract.passage``, the rule of every stage)."""
    return passage(table["s_rev"].to_numpy(), table["A_xx"].to_numpy(), table["A_xy"].to_numpy(), noisy=False)["axis"]


def _envelopes(curves, nominal):
    """Per envelope: (lower curves, upper curves, runs, failed runs); theta_A spread about the fitted curve."""
    envelopes = {}
    for env in ("interval", "5%", "1%"):
        tabs = curves.get(env, [])
        ok = [t for t in tabs if t is not None]
        if not tabs:
            continue
        lo, hi = {}, {}
        if ok:
            for q in QUANTITIES:
                if q == "theta_A" and nominal.table is not None:
                    ref = nominal.table[q].to_numpy()
                    dev = np.array([angle_difference(t[q], ref) for t in ok])
                    lo[q], hi[q] = ref + dev.min(axis=0), ref + dev.max(axis=0)
                else:
                    arr = np.array([t[q].to_numpy() for t in ok])
                    lo[q], hi[q] = arr.min(axis=0), arr.max(axis=0)
        envelopes[env] = (lo, hi, len(tabs), len(tabs) - len(ok))
    return envelopes
