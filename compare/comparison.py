r"""One calibration set against every DEM case: predictions, errors, claims.

Two levels of comparison:

- ``seed``: each DEM run against the model integrated on that run's own
  history from that run's fabric; errors on the run's samples.
- ``ensemble``: the seeds of one (pressure, I) ensemble averaged on the first
  seed's ``s_rev`` grid (cut to the shortest run): the fabric components and mu
  are averaged, then |A| and theta_A taken from the mean fabric (the fabric of
  the pooled contacts); the models' per-seed curves are averaged the same way.
  The DEM band is one standard deviation over seeds of each seed's own |A|,
  theta_A (modulo 180) and mu about the ensemble value.

Every reversal of every protocol is compared, one ensemble per transient (a
schedule's k-th reversal across seeds, ``transient_groups``); each row names the
reversal's ``kind`` (heaviside: a step; sinusoidal: a half cosine), its number
in its run (``reversal``) and its ``direction`` (-1 against the pre-shear, +1
back along it). The model is integrated in the run's own frame; the curves of a
+1 reversal (``predictions.csv``, the claims, the figures) are then reflected
x -> -x into the frame of the -1 ones (``dem.canonical``). Errors do not change
under the reflection.

Claims (``metrics.claims``) are measured on the DEM after a centred running
mean over ``dem_smooth`` samples (its noise otherwise sets the minima), and on
the models as they are. The steady values the recovery is measured against are
the DEM's pre-shear steady state for the DEM (``dem_contract.steady_values``;
for an ensemble, |A| of the seeds' mean steady fabric and their mean mu), and
each model's own steady state (``model.steady_state``) for the models.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import pandas as pd

from dem_contract import DEMInputError, angle_difference, fabric_angle_deg, fabric_norm
from model import load_params, steady_state

from . import metrics
from .dem import canonical, load_reversals
from .predict import DEFAULT_FRICTION, MODELS, predict
from .metrics import QUANTITIES

DEM_SMOOTH = 5


@dataclass
class Comparison:
    """Everything one ``compare predict`` run produces (see ``run``)."""

    predictions: pd.DataFrame
    errors: pd.DataFrame
    claims: pd.DataFrame
    ensembles: dict = field(default_factory=dict)   # (group, protocol) -> DataFrame for the figures


def ensemble_curves(revs, preds):
    """Seed-averaged DEM and model curves of one (group, protocol).

    Parameters
    ----------
    revs : list of compare.dem.Reversal
        The seeds of one ensemble and protocol.
    preds : dict
        model -> list of Prediction (same order as ``revs``).

    Returns
    -------
    DataFrame
        ``s_rev``; ``dem_<q>`` and ``dem_<q>_std`` for q in QUANTITIES,
        ``dem_A_xx``, ``dem_A_xy``; ``<model>_<q>``, ``<model>_A_xx``,
        ``<model>_A_xy`` (NaN when every seed failed) and the attribute
        ``attrs["n_ok"]`` = {model: seeds integrated}.
    """
    s = revs[0].data["s_rev"].to_numpy()
    s = s[s <= min(r.data["s_rev"].iloc[-1] for r in revs) + 1e-12]

    def on_grid(sr, df):
        return {c: np.interp(s, sr, df[c].to_numpy()) for c in ("A_xx", "A_xy", "mu")}

    dem = [on_grid(r.data["s_rev"].to_numpy(), r.data) for r in revs]
    out = {"s_rev": s}
    a = np.mean([d["A_xx"] for d in dem], axis=0)
    b = np.mean([d["A_xy"] for d in dem], axis=0)
    out.update(dem_A_xx=a, dem_A_xy=b, dem_A_norm=fabric_norm(a, b), dem_theta_A=fabric_angle_deg(a, b),
               dem_mu=np.mean([d["mu"] for d in dem], axis=0))
    ddof = 1 if len(dem) > 1 else 0
    out["dem_A_norm_std"] = np.std([fabric_norm(d["A_xx"], d["A_xy"]) for d in dem], axis=0, ddof=ddof)
    dev = [angle_difference(fabric_angle_deg(d["A_xx"], d["A_xy"]), out["dem_theta_A"]) for d in dem]
    out["dem_theta_A_std"] = np.sqrt(np.sum(np.square(dev), axis=0) / max(len(dem) - ddof, 1))
    out["dem_mu_std"] = np.std([d["mu"] for d in dem], axis=0, ddof=ddof)
    n_ok = {}
    for model, plist in preds.items():
        ok = [on_grid(r.data["s_rev"].to_numpy(), p.table) for r, p in zip(revs, plist) if p.table is not None]
        n_ok[model] = len(ok)
        if ok:
            a = np.mean([d["A_xx"] for d in ok], axis=0)
            b = np.mean([d["A_xy"] for d in ok], axis=0)
            m = np.mean([d["mu"] for d in ok], axis=0)
        else:
            a = b = m = np.full_like(s, np.nan)
        out.update({f"{model}_A_xx": a, f"{model}_A_xy": b, f"{model}_A_norm": fabric_norm(a, b),
                    f"{model}_theta_A": fabric_angle_deg(a, b), f"{model}_mu": m})
    df = pd.DataFrame(out)
    df.attrs["n_ok"] = n_ok
    df.attrs["n_seeds"] = len(revs)
    return df


def model_steady(params, model, friction, sign):
    """|A| and mu of a model's own steady state for the sign of the rate (NaN if it has none)."""
    try:
        a, b, X = steady_state(params, model, sign=sign)
    except ValueError:
        return float("nan"), float("nan")
    from model import friction_eq2, friction_quadratic
    if friction == "eq2":
        f = params.friction_eq2
        mu = friction_eq2(X, f.X0, f.k1, f.k3, f.k5)
    else:
        f = params.friction_quadratic
        mu = friction_quadratic(X, f.m0, f.m1, f.m2)
    return float(fabric_norm(a, b)), float(mu)


def _claims_row(base, source, s, a, b, mu, steady_A, steady_mu, smooth):
    row = dict(base, source=source, steady_A=steady_A, steady_mu=steady_mu, smooth=smooth)
    if np.all(np.isfinite(a)):
        row.update(metrics.claims(s, a, b, mu, steady_A, steady_mu, smooth=smooth), status="ok")
    else:
        row["status"] = "no curve"
    return row


def run(case_dirs, params_path, protocols, set_name="all", train_cases=None, train_protocols=None,
        friction=None, dem_smooth=DEM_SMOOTH) -> Comparison:
    """Predict every case and protocol with one parameter file and compare.

    Parameters
    ----------
    case_dirs : list of path
        DEM case directories ``.../<label>``.
    params_path : path
        ``params.yaml`` of the calibration set.
    protocols : list of str
        Reversal protocols to compare.
    set_name : str
        Name of the calibration set (a column of every table).
    train_cases, train_protocols : list of str, optional
        What the set was calibrated on (default: everything): a row is
        ``in_sample`` when its case(s) and protocol are all in them.
    friction : dict, optional
        model -> friction law; default ``predict.DEFAULT_FRICTION``.
    dem_smooth : int
        Running-mean width applied to the DEM before measuring claims.
    """
    params = load_params(params_path)
    friction = dict(DEFAULT_FRICTION, **(friction or {}))
    labels = [str(getattr(d, "name", d)).rstrip("/").split("/")[-1] for d in case_dirs]
    train_cases = set(labels if train_cases is None else train_cases)
    train_protocols = set(protocols if train_protocols is None else train_protocols)
    pred_rows, err_rows, claim_rows, ensembles = [], [], [], {}
    steady = {}
    for protocol, key, revs in transient_groups(case_dirs, protocols):
        preds = {m: [predict(r, params, m, friction[m]) for r in revs] for m in MODELS}
        sign = -1 if np.median(revs[0].data["gammadot"].to_numpy()[-5:]) < 0 else 1
        for m in MODELS:
            steady.setdefault((m, sign), model_steady(params, m, friction[m], sign))
        steady_here = {m: steady[(m, sign)] for m in MODELS}
        # from here on every curve in the frame of the -1 reversals (a +1 one reflected x -> -x)
        preds = {m: [replace(p, table=canonical(r, p.table)) for r, p in zip(revs, plist)]
                 for m, plist in preds.items()}
        revs = [replace(r, data=canonical(r)) for r in revs]
        tags = dict(kind=revs[0].kind, reversal=revs[0].reversal, direction=revs[0].direction)
        for i, r in enumerate(revs):
            base = dict(set=set_name, level="seed", case=r.label, group=r.group, protocol=key,
                        in_sample=r.label in train_cases and protocol in train_protocols)
            curves, errors, claims = seed_rows(r, {m: preds[m][i] for m in MODELS}, base, steady_here, dem_smooth)
            pred_rows += [c.assign(**tags) for c in curves]
            err_rows += [dict(e, **tags) for e in errors]
            claim_rows += [dict(c, **tags) for c in claims]
        for group in dict.fromkeys(r.group for r in revs):
            idx = [i for i, r in enumerate(revs) if r.group == group]
            grevs = [revs[i] for i in idx]
            base = dict(set=set_name, level="ensemble", case=group, group=group, protocol=key,
                        in_sample=all(r.label in train_cases for r in grevs) and protocol in train_protocols)
            ens, errors, claims = _ensemble_rows(grevs, {m: [preds[m][i] for i in idx] for m in MODELS}, base,
                                                 steady_here, friction, dem_smooth)
            ens.attrs.update(tags, protocol=key)
            ensembles[(group, key)] = ens
            err_rows += [dict(e, **tags) for e in errors]
            claim_rows += [dict(c, **tags) for c in claims]
    return Comparison(predictions=pd.concat(pred_rows, ignore_index=True), errors=tags_last(pd.DataFrame(err_rows)),
                      claims=tags_last(pd.DataFrame(claim_rows)), ensembles=ensembles)


TAG_COLUMNS = ("kind", "reversal", "direction")


def tags_last(df: pd.DataFrame) -> pd.DataFrame:
    """The reversal's ``kind``, ``reversal`` and ``direction`` as the table's last columns."""
    return df[[c for c in df.columns if c not in TAG_COLUMNS] + [c for c in TAG_COLUMNS if c in df.columns]]


def transient_groups(case_dirs, protocols):
    """``(protocol, key, reversals)`` for every transient the runs hold (``dem.load_reversals``).

    A heaviside or sinusoidal protocol is one group under its own name; a reversal
    schedule with several reversals one group per reversal, ``<protocol>_r<k>``, holding
    the k-th reversal of every case that ran it (the same kind, direction and place in
    the schedule across seeds, so they form one ensemble).

    Raises
    ------
    DEMInputError
        When the k-th reversals of a schedule differ in kind or direction between cases.
    """
    for protocol in protocols:
        per_case = [load_reversals(d, protocol) for d in case_dirs_with(case_dirs, protocol)]
        n = max(len(revs) for revs in per_case)
        for k in range(n):
            group = [revs[k] for revs in per_case if len(revs) > k]
            tags = {(r.kind, r.direction) for r in group}
            if len(tags) > 1:
                raise DEMInputError(f"reversal {k + 1} of {protocol} differs between cases (kind, direction): "
                                    + ", ".join(f"{r.path}: {r.kind} {r.direction:+d}" for r in group))
            yield protocol, (protocol if n == 1 else f"{protocol}_r{k + 1}"), group


def case_dirs_with(case_dirs, protocol):
    """The case directories that hold a ``<protocol>.csv`` run (cases may hold different protocols).

    Raises
    ------
    DEMInputError
        When none does (the protocol was asked for, but no case ran it).
    """
    # a missing case directory is kept: reading it reports it as not found
    dirs = [d for d in case_dirs if not Path(d).is_dir() or (Path(d) / f"{protocol}.csv").exists()]
    if not dirs:
        raise DEMInputError(f"no case holds a {protocol} run ({protocol}.csv missing in "
                            f"{', '.join(str(d) for d in case_dirs)}); drop it from --protocols")
    return dirs


CURVE_COLUMNS = ("s_rev", "strain", "A_xx", "A_xy", "A_norm", "theta_A", "mu")


def _curve_frame(base, r, source, table):
    """Rows of ``predictions.csv``: one curve (the DEM's or a model's) of one run."""
    return pd.DataFrame(dict(set=base["set"], case=r.label, group=r.group, seed=r.seed, protocol=base["protocol"],
                             source=source, **{c: table[c] for c in CURVE_COLUMNS}))


def _curve_arrays(table):
    """``s_rev, A_xx, A_xy, mu`` of a curve, as ``metrics.claims`` takes them."""
    return tuple(table[c].to_numpy() for c in ("s_rev", "A_xx", "A_xy", "mu"))


def seed_rows(r, preds, base, steady, dem_smooth):
    """Curves, error rows and claim rows of one DEM run and its predictions (``preds``: model -> Prediction).

    ``steady``: model -> (|A|, mu) of the model's own steady state, the reference of its claims.
    """
    d = r.data
    curves = [_curve_frame(base, r, "dem", d)]
    claims = [_claims_row(base, "dem", *_curve_arrays(d), r.steady_A, r.steady_mu, dem_smooth)]
    errors = []
    for m, p in preds.items():
        row = dict(base, model=m, friction=p.friction, status=p.status, rate_smoothing=p.rate_smoothing,
                   strain_mismatch=p.strain_mismatch, n_samples=len(d))
        if p.table is not None:
            row.update(metrics.errors(d, p.table))
            curves.append(_curve_frame(base, r, m, p.table))
            claims.append(_claims_row(base, m, *_curve_arrays(p.table), *steady[m], 1))
        else:
            claims.append(dict(base, source=m, status=p.status))
        errors.append(row)
    return curves, errors, claims


def _ensemble_rows(grevs, gpreds, base, steady, friction, dem_smooth):
    """Seed-averaged curves of one ensemble and protocol, with their error and claim rows.

    The DEM's claims are measured against the ensemble's steady |A| and mu (pre-shear);
    a model's status says how many seeds failed.
    """
    ens = ensemble_curves(grevs, gpreds)
    s = ens["s_rev"].to_numpy()
    steady_fabric = np.mean([r.steady_fabric for r in grevs], axis=0)
    claims = [_claims_row(base, "dem", s, ens["dem_A_xx"].to_numpy(), ens["dem_A_xy"].to_numpy(),
                          ens["dem_mu"].to_numpy(), float(fabric_norm(*steady_fabric)),
                          float(np.mean([r.steady_mu for r in grevs])), dem_smooth)]
    dem = {q: ens[f"dem_{q}"].to_numpy() for q in QUANTITIES}
    errors = []
    for m in MODELS:
        n_ok = ens.attrs["n_ok"][m]
        status = "ok" if n_ok == len(grevs) else f"{len(grevs) - n_ok} of {len(grevs)} seeds failed"
        row = dict(base, model=m, friction=friction[m], status=status, n_samples=len(ens))
        claim = dict(base, source=m, status=status)
        if n_ok:
            row.update(metrics.errors(dem, {q: ens[f"{m}_{q}"].to_numpy() for q in QUANTITIES}))
            claim = _claims_row(base, m, s, ens[f"{m}_A_xx"].to_numpy(), ens[f"{m}_A_xy"].to_numpy(),
                                ens[f"{m}_mu"].to_numpy(), *steady[m], 1)
            claim["status"] = status
        errors.append(row)
        claims.append(claim)
    return ens, errors, claims
