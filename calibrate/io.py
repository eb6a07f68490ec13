r"""Read and validate the DEM time series (docs/data-contract.md).

A *case directory* ``results/dem/<case>/`` holds ``preshear.csv``,
``heaviside.csv``, ``sinusoidal.csv`` (and a CSV per reversal schedule) and
JSON sidecars. Each reversal within a run is one transient
(``transient_runs``). Its name encodes
pressure, inertial number and seed (``p<P>_I<I>_s<seed>``); cases that differ
only by the seed form one *ensemble*.

Everything is checked here, at the entrance, and every problem raises
:class:`DEMInputError` naming the file and what is wrong: a missing file or
column, a NaN or infinity in a column the calibration uses, too few samples,
times that do not increase (these are the contract's checks, in
``dem_contract.read_series``), a non-positive pressure, a reversal file
without a reversal, and a pre-shear that never reached steady state (these are
the calibration's own). Nothing downstream re-checks.

Every contract column must be present; columns beyond the contract are ignored.
The case labels, the steady window, the fabric's norm and angle and the
pre-reversal state are ``dem_contract``'s (``labels``, ``derived``), the same
numbers the campaign summary and the comparison report.
"""
from __future__ import annotations

import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.stats import t as student_t

from dem_contract import (CONTRACT_COLUMNS, REVERSAL_PROTOCOLS, STEADY_FRACTION, DEMInputError, derived,
                          fabric_angle_deg, fabric_norm, pre_reversal_state, read_series, read_sidecar,
                          reversal_indices, split_case_label, split_transients, steady_window)

#: The columns the calibration computes with: they must be finite in every row.
USED_COLUMNS = ("t", "strain", "gammadot", "A_xx", "A_xy", "sigma_xy", "p", "mu")

MIN_SAMPLES = 50            # rows per file
STEADY_WINDOW = STEADY_FRACTION  # last fraction of the pre-shear strain judged for steadiness (dem_contract)
STEADY_REL_TOL = 0.1        # allowed drift across that window, relative to the level
STEADY_SE_FACTOR = 4.0      # ... or this many standard errors of the drift, if larger


@dataclass
class Run:
    """One validated DEM run (one CSV).

    Attributes
    ----------
    path : Path
    case : str
        Case directory name.
    group : str
        Ensemble key (the case name without its seed).
    seed : str
    protocol : str
        ``preshear``, ``heaviside``, ``sinusoidal``, or a reversal schedule's name; one
        transient of a schedule with several reversals is ``<schedule>_r<k>``.
    data : pandas.DataFrame
        The contract columns, rows in time order.
    meta : dict
        The JSON sidecar (empty if absent).
    schedule : str, optional
        For one transient of a multi-reversal run: the run's protocol (its file's name).
    initial_state : dict, optional
        For such a transient: the state just before its reversal
        (``dem_contract.split_transients``); None: the end of the pre-shear.
    """

    path: Path
    case: str
    group: str
    seed: str
    protocol: str
    data: pd.DataFrame
    meta: dict = field(default_factory=dict)
    schedule: str | None = None
    initial_state: dict | None = None

    @property
    def label(self) -> str:
        return f"{self.case}/{self.protocol}"


@dataclass
class Case:
    """The runs of one case directory (one seed)."""

    path: Path
    name: str
    group: str
    seed: str
    preshear: Run
    runs: dict  # protocol -> Run


def read_run(path, protocol: str, min_samples: int = MIN_SAMPLES) -> Run:
    """Read one CSV of the contract and check it.

    Parameters
    ----------
    path : str or Path
        ``<case>/<protocol>.csv``.
    protocol : str
    min_samples : int
        Fewest rows accepted.

    Raises
    ------
    DEMInputError
        Missing file or column (every contract column is required),
        non-numeric or non-finite values in a used column, fewer than
        ``min_samples`` rows, time not increasing (``dem_contract.read_series``);
        non-positive pressure; an invalid sidecar. (``read_case`` adds: a
        reversal run whose rate never opposes the pre-shear's.)
    """
    path = Path(path)
    data = read_series(path, columns=CONTRACT_COLUMNS, finite=USED_COLUMNS, min_samples=min_samples,
                       what=f"the {protocol} run of the case")
    if np.any(data["p"].to_numpy() <= 0):
        raise DEMInputError(f"{path}: column 'p' has non-positive values")
    meta = read_sidecar(path)
    case = path.parent.name
    group, seed = split_case_label(case)
    return Run(path=path, case=case, group=group, seed=seed, protocol=protocol, data=data, meta=meta)


def check_steady(run: Run, window: float = STEADY_WINDOW, rel_tol: float = STEADY_REL_TOL,
                 se_factor: float = STEADY_SE_FACTOR, raise_on_drift: bool = True) -> dict:
    r"""Check that a pre-shear ended in steady state and return its steady values.

    Rule: over the last ``window`` fraction of the run's strain
    (``dem_contract.steady_window``), fit a straight
    line in strain to A_xx, A_xy and mu. The drift it predicts across the
    window must be below ``max(rel_tol * level, se_factor * SE(drift))``, with
    ``level`` the window mean of |A| (fabric) or of mu, and SE(drift) corrected
    for the serial correlation of the samples (``ar1_variance_inflation``).

    Returns
    -------
    dict
        The steady values of the window (``dem_contract.steady_values``: the
        means ``A_xx, A_xy, mu``, ``A_norm``, ``theta_A``, ...), the standard
        errors ``se_A_xx, se_A_xy, se_mu`` of the three means, and
        ``drift_error``: the message of the first quantity that drifts, or None.

    Raises
    ------
    DEMInputError
        Naming the file, the quantity and its drift (only with ``raise_on_drift``).
    """
    d = run.data
    drift = _drift_test(run.path, d["strain"].to_numpy(), {c: d[c].to_numpy() for c in ("A_xx", "A_xy", "mu")},
                        window, rel_tol, se_factor, raise_on_drift)
    return {**derived.steady_values(d, window), **drift}


def _drift_test(path, strain, series, window, rel_tol, se_factor, raise_on_drift) -> dict:
    """The drift test of ``check_steady`` on arrays (one run, or an ensemble mean): ``drift_error`` and ``se_*``."""
    if np.abs(strain[-1] - strain[0]) <= 0:
        raise DEMInputError(f"{path}: the strain does not advance")
    m = steady_window(strain, window)
    s = np.abs(strain - strain[0])
    if m.sum() < 10:
        raise DEMInputError(f"{path}: fewer than 10 samples in the last {window:.0%} of the strain; cannot judge steady state")
    x = s[m] - s[m].mean()
    a, b, mu = (series[c][m] for c in ("A_xx", "A_xy", "mu"))
    level_A = float(np.mean(fabric_norm(a, b)))
    out = {"drift_error": None}
    for name, y, level in (("A_xx", a, level_A), ("A_xy", b, level_A), ("mu", mu, float(np.mean(mu)))):
        slope, icpt = np.polyfit(x, y, 1)
        resid = y - (slope * x + icpt)
        sd = float(np.std(resid, ddof=2))
        inflation = np.sqrt(ar1_variance_inflation(resid))
        se_slope = inflation * sd / np.sqrt(np.sum(x**2))
        width = x.max() - x.min()
        drift = slope * width
        tol = max(rel_tol * abs(level), se_factor * se_slope * width)
        if abs(drift) > tol and out["drift_error"] is None:
            out["drift_error"] = (
                f"{path}: the pre-shear never reached steady state: {name} still drifts by "
                f"{drift:+.4g} over the last {window:.0%} of the strain (tolerance {tol:.3g})"
            )
            if raise_on_drift:
                raise DEMInputError(out["drift_error"])
        out[f"se_{name}"] = inflation * sd / np.sqrt(len(y))
    return out


def check_steady_ensemble(cases) -> list:
    """Judge the steady state of each group of seeds on its ensemble mean.

    One ~500-disk run wanders slowly (shear bands move; its fabric is
    correlated over tenths of strain), so a single run can fail the drift
    test of ``check_steady`` while the ensemble is steady. A group whose runs
    all pass is accepted; otherwise the seeds' pre-shears are averaged on a
    common strain grid and the same test is applied to the mean. A group whose
    mean still drifts is an error naming its files.

    Returns
    -------
    list of str
        The single-run drift messages that the ensemble overruled (warnings).
    """
    warnings = []
    for group in sorted({c.group for c in cases}):
        members = [c for c in cases if c.group == group]
        failed = [c.preshear.meta["steady"]["drift_error"] for c in members]
        failed = [f for f in failed if f]
        if not failed:
            continue
        if len(members) == 1:
            raise DEMInputError(failed[0])
        runs = [c.preshear.data for c in members]
        span = min(np.abs(r["strain"].to_numpy() - r["strain"].iloc[0])[-1] for r in runs)
        grid = np.linspace(0.0, span, max(len(r) for r in runs))
        mean = {c: np.mean([np.interp(grid, np.abs(r["strain"].to_numpy() - r["strain"].iloc[0]), r[c].to_numpy())
                            for r in runs], axis=0) for c in ("A_xx", "A_xy", "mu")}
        files = ", ".join(str(c.preshear.path) for c in members)
        result = _drift_test(f"the mean of {len(members)} seeds of {group} ({files})", grid, mean,
                             STEADY_WINDOW, STEADY_REL_TOL, STEADY_SE_FACTOR, raise_on_drift=True)
        warnings += [f"{f} (single run; the ensemble of {group} is steady)" for f in failed]
        assert result["drift_error"] is None
    return warnings


def ar1_variance_inflation(resid) -> float:
    r"""Factor by which serial correlation inflates the variance of a mean or slope.

    DEM samples of one run are correlated over a few hundredths of strain (the
    contact network lives that long), so the white-noise standard error is too
    small. With the lag-1 autocorrelation :math:`r` of the residuals (clipped to
    [0, 0.95]), an AR(1) model gives the factor :math:`(1 + r)/(1 - r)`.
    """
    resid = np.asarray(resid, dtype=float)
    r = float(np.corrcoef(resid[:-1], resid[1:])[0, 1]) if len(resid) > 2 else 0.0
    r = min(max(r if np.isfinite(r) else 0.0, 0.0), 0.95)
    return (1.0 + r) / (1.0 - r)


def read_case(case_dir, protocols=REVERSAL_PROTOCOLS, min_samples: int = MIN_SAMPLES) -> Case:
    """Read a case directory: its pre-shear (checked for steady state) and the chosen reversal runs it has.

    A case need not hold every protocol (a campaign may run the sinusoidal
    reversal for some seeds only): each reversal run present is one transient
    and the absent ones are skipped. A case with none of ``protocols`` is an
    error naming the directory.
    """
    case_dir = Path(case_dir)
    if not case_dir.is_dir():
        raise DEMInputError(f"{case_dir}: case directory not found")
    pre = read_run(case_dir / "preshear.csv", "preshear", min_samples)
    pre.meta["steady"] = check_steady(pre, raise_on_drift=False)  # judged per group in read_cases
    present = [p for p in protocols if (case_dir / f"{p}.csv").exists()]
    if not present:
        raise DEMInputError(f"{case_dir}: no reversal run of the protocols {', '.join(protocols)} "
                            f"(expected at least one of {', '.join(f'{p}.csv' for p in protocols)})")
    runs = {}
    g_pre = pre.data["gammadot"].to_numpy()
    for p in present:
        r = read_run(case_dir / f"{p}.csv", p, min_samples)
        if reversal_indices(np.concatenate([g_pre, r.data["gammadot"].to_numpy()])).size == 0:
            raise DEMInputError(f"{r.path}: 'gammadot' never takes the sign opposite to the pre-shear's "
                                f"(for {derived.REVERSAL_MIN_RUN} samples in a row): no reversal in this {r.protocol} run")
        runs.update(transient_runs(pre, r, min_samples))
    group, seed = split_case_label(case_dir.name)
    return Case(path=case_dir, name=case_dir.name, group=group, seed=seed, preshear=pre, runs=runs)


def transient_runs(pre: Run, run: Run, min_samples: int = MIN_SAMPLES) -> dict:
    """A reversal run as the transients the calibration fits: protocol -> Run.

    A run with one reversal (heaviside, sinusoidal) is one transient, kept whole under
    its protocol. A reversal schedule's run with several reversals
    (``dem_contract.split_transients``) gives one Run per reversal, ``<protocol>_r<k>``,
    holding its rows from that reversal to the next and the state just before it
    (``initial_state``), whichever direction it shears in.
    """
    transients = split_transients(pre.data, run.data, run.meta, what=str(run.path))
    if len(transients) == 1:
        return {run.protocol: run}
    out = {}
    for tr in transients:
        name = f"{run.protocol}_r{tr.index}"
        if len(tr.data) < min_samples:
            raise DEMInputError(f"{run.path}: only {len(tr.data)} samples after reversal {tr.index} "
                                f"(t = {tr.t0:g}), at least {min_samples} are needed (--min-samples)")
        out[name] = Run(path=run.path, case=run.case, group=run.group, seed=run.seed, protocol=name, data=tr.data,
                        meta=dict(run.meta, reversal=tr.index), schedule=run.protocol, initial_state=tr.initial)
    return out


def read_cases(case_dirs, protocols=REVERSAL_PROTOCOLS, min_samples: int = MIN_SAMPLES) -> list:
    """Read several case directories; seeds must be distinct within a group.

    Cases may hold different sets of protocols (``read_case``); every
    protocol asked for must be present in at least one case.
    """
    if not case_dirs:
        raise DEMInputError("no case directory given")
    cases = [read_case(c, protocols, min_samples) for c in case_dirs]
    for p in protocols:
        if not any(p in c.runs or any(r.schedule == p for r in c.runs.values()) for c in cases):
            raise DEMInputError(f"no case holds a {p} run ({p}.csv missing in "
                                f"{', '.join(str(c.path) for c in cases)}); drop it from --protocols")
    seen = set()
    for c in cases:
        key = (c.group, c.seed)
        if key in seen:
            raise DEMInputError(f"{c.path}: seed {c.seed} of {c.group} given twice")
        seen.add(key)
    for warning in check_steady_ensemble(cases):
        print(f"calibrate: warning: {warning}", file=sys.stderr)
    return cases


def steady_values(cases) -> dict:
    r"""Ensemble steady state from the pre-shear tails (mean over seeds, SE from their scatter).

    Returns ``A_xx, A_xy, X, mu, A_norm, theta_A`` and ``se_*`` (X = sqrt2 A_xy for
    the positive pre-shear direction). With one seed the SE is the run's own.
    ``X_reversal_max`` is the largest mirrored X a run's reversal starts from
    (``dem_contract.pre_reversal_state``), ``X_reversal_bound`` the larger of it
    and the upper 97.5 % prediction bound of that X for a new seed,
    :math:`\bar x + t_{0.975, n-1}\, s \sqrt{1 + 1/n}`: Model 1's pole must lie
    beyond it, or a new run may start past the pole.
    """
    rows = []
    starts = [pre_reversal_state(c.preshear.data) for c in cases]   # also the pre-shear's direction g
    for c, start in zip(cases, starts):
        st = c.preshear.meta["steady"]
        g = start["gammadot_sign"]
        rows.append((st["A_xx"], st["A_xy"] * g, st["mu"], st["se_A_xx"], st["se_A_xy"], st["se_mu"]))
    r = np.array(rows)
    n = len(r)
    mean = r[:, :3].mean(axis=0)
    if n > 1:
        se = r[:, :3].std(axis=0, ddof=1) / np.sqrt(n)
        se = np.maximum(se, np.sqrt((r[:, 3:] ** 2).mean(axis=0) / n))
    else:
        se = r[0, 3:]
    a, b, mu = mean
    out = {"A_xx": a, "A_xy": b, "mu": mu, "se_A_xx": se[0], "se_A_xy": se[1], "se_mu": se[2],
           "X": np.sqrt(2) * b, "se_X": np.sqrt(2) * se[1], "n_seeds": n}
    out["A_norm"] = float(fabric_norm(a, b))
    out["theta_A"] = float(fabric_angle_deg(a, b))
    # the X a reversal starts from (mirrored state at the end of each pre-shear): the largest
    # seen, and the upper 97.5 % prediction bound for a new seed (Student t over the seeds)
    xr = np.array([-start["X"] for start in starts])
    out["X_reversal_max"] = float(xr.max())
    out["X_reversal_bound"] = reversal_start_bound(xr)
    return {k: float(v) for k, v in out.items()}


def reversal_start_bound(x, level=0.975) -> float:
    r"""Largest of ``x`` and its upper prediction bound for one more draw.

    .. math:: \bar x + t_{level, n-1}\, s \sqrt{1 + 1/n}

    (Student t, s the sample standard deviation); ``max(x)`` for a single value.
    """
    x = np.asarray(x, dtype=float)
    if len(x) < 2:
        return float(x.max())
    n = len(x)
    return float(max(x.mean() + student_t.ppf(level, n - 1) * x.std(ddof=1) * np.sqrt(1 + 1 / n), x.max()))
