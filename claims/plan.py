r"""The planner: how many seeds (and core-hours) decide every claim the table leaves undecided.

``python -m claims plan`` (and the rule ``claims_plan``) reads the claims table
(``paper_claims.csv``: each row's estimate, null, margin, seed-to-seed s.d. and
number of seeds) and the campaign's measured stage costs, and writes
``plan.csv``: for every **inconclusive** row (each figure's row of a model
comparison included) the seeds that decide it at ``power.POWER`` (80 %)
power, at the measured effect, either way, at the table's one level:

- *reproduced* or *contradicted* (the side of the null the estimate is on):
  the smallest :math:`n` whose 90 % t interval excludes the null on that side
  (one-sided 5 %) with 80 % power (``power.seeds_needed``, noncentral t);
- *negligible* (only if :math:`|\hat\delta| < m`, the claim's margin): the
  smallest :math:`n` at which the 90 % interval lies inside :math:`\pm m`
  with 80 % power, two one-sided tests (``power_tost``):

  .. math:: P_{TOST}(n) \ge F_{t'}\!\big(-t_{0.95,n-1};\ n-1,\ (\delta - m)\sqrt n/s\big)
            + 1 - F_{t'}\!\big(t_{0.95,n-1};\ n-1,\ (\delta + m)\sqrt n/s\big) - 1

  (the Bonferroni bound of the joint probability: a lower bound, so ``n`` is
  an upper bound).

The cheaper route is the plan (``outcome``). The table's intervals are the
wider of a bootstrap and the t interval, so with few seeds these counts are
lower bounds of the seeds the table needs. Seeds are the table's unit: DEM
cases, pooled across ensembles; ``config_seeds_to_add`` divides the cases to
add by the ensembles (pressures x inertial numbers), since one more entry of
``seeds:`` adds a case to each. A new seed runs a packing, a pre-shear and
every reversal protocol; its core-hours are the campaign's mean measured CPU
time of those stages (``power.dem_cost``); when the sidecars do not say, the
cost is ``unknown`` (not a number). Extending ``seeds:`` reruns no finished
seed: only the new cases' DEM is planned (tests/test_claims_plan.py).
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from dem_contract import REVERSAL_PROTOCOLS, DEMInputError, split_case_label

from . import power

EQUIVALENCE_ALPHA = 0.05    # each of the two one-sided tests
COLUMNS = ["claim_id", "claim", "verdict", "estimate", "null", "margin", "sd", "seeds_now", "outcome",
           "seeds_needed", "cases_to_add", "config_seeds_to_add", "core_hours", "wall_hours_2_cores",
           "wall_hours_cluster", "seeds_sided", "sided_outcome",
           "seeds_negligible", "note"]


def power_tost(n, sd: float, delta: float, margin: float, alpha: float = EQUIVALENCE_ALPHA) -> float:
    r"""Lower bound of the probability that ``n`` values' 90 % t interval lies inside +-``margin`` (module docstring).

    Parameters
    ----------
    n : int
        Seeds, at least 2.
    sd : float
        Their standard deviation.
    delta : float
        The true effect (about the null).
    margin : float
        The equivalence margin, > 0.
    """
    if n < 2 or not (np.isfinite(sd) and sd > 0 and np.isfinite(delta) and np.isfinite(margin) and margin > 0):
        return math.nan
    df = n - 1
    crit = stats.t.ppf(1.0 - alpha, df)
    se = sd / math.sqrt(n)
    p = stats.nct.cdf(-crit, df, (delta - margin) / se) + stats.nct.sf(crit, df, (delta + margin) / se) - 1.0
    return float(max(p, 0.0))


def seeds_tost(sd: float, delta: float, margin: float, target: float = power.POWER) -> float:
    """Smallest n >= 2 with ``power_tost(n) >= target``; ``inf`` if ``|delta| >= margin`` or beyond ``power.N_MAX``.

    Bisection between 2 and a bracket found by doubling (the power grows with n).
    """
    if not (np.isfinite(sd) and sd > 0 and np.isfinite(delta) and np.isfinite(margin) and margin > 0):
        return math.nan
    if abs(delta) >= margin:
        return math.inf
    hi = 2
    while power_tost(hi, sd, delta, margin) < target:
        hi *= 2
        if hi > power.N_MAX:
            return math.inf
    lo = max(2, hi // 2)
    if power_tost(lo, sd, delta, margin) >= target:
        return float(lo)
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if power_tost(mid, sd, delta, margin) >= target:
            hi = mid
        else:
            lo = mid
    return float(hi)


def ensembles_of(case_dirs) -> int:
    """Number of ensembles (``p.._I..`` groups) among the case directories (at least 1)."""
    return max(1, len({split_case_label(Path(d).name)[0] for d in case_dirs}))


def _hours(cases: float, seed_cpu_s: float):
    if cases == 0:
        return 0.0
    if not np.isfinite(cases):
        return "inf" if cases == math.inf else "unknown"
    if not (np.isfinite(seed_cpu_s) and seed_cpu_s > 0):
        return "unknown"
    return round(cases * seed_cpu_s / 3600.0, 4)


def wall_hours(core_hours, seed_cpu_s: float, cores: int | None) -> float | str:
    r"""Wall hours of the DEM that adds ``core_hours``: on ``cores`` one-thread jobs, or one core per case (None).

    .. math:: T_{2} = C / 2, \qquad T_{\mathrm{cluster}} = c_{\mathrm{seed}}

    (every case's chain packing -> pre-shear -> protocols on its own node through the Slurm profile:
    the longest chain, one seed's CPU time ``seed_cpu_s``; its protocols run after one another here,
    so this is an upper bound). ``core_hours``' own text (``unknown``, ``inf``) passes through.
    """
    if not isinstance(core_hours, (int, float)):
        return core_hours
    if core_hours == 0:
        return 0.0
    return round(core_hours / cores, 4) if cores else round(seed_cpu_s / 3600.0, 4)


def plan_table(table: pd.DataFrame, seed_cpu_s: float, ensembles: int = 1) -> pd.DataFrame:
    """One row per inconclusive claim of ``table`` (``COLUMNS``).

    Parameters
    ----------
    table : DataFrame
        The claims table (``claims.table.COLUMNS``: estimate, null, paper_side, margin, sd, n, verdict).
    seed_cpu_s : float
        Measured CPU seconds of one more case (packing, pre-shear and every protocol); NaN if unknown.
    ensembles : int
        Cases that one more entry of the config's ``seeds:`` adds.
    """
    rows = []
    for _, r in table.iterrows():
        if str(r["verdict"]) != "inconclusive":
            continue
        sd, n_now = float(r.get("sd", math.nan)), int(r["n"]) if np.isfinite(r["n"]) else 0
        delta = float(r["estimate"]) - float(r["null"])
        margin = float(r.get("margin", math.nan))
        sided = power.seeds_needed(sd, delta) if delta != 0 else math.inf
        sided_outcome = ("reproduced" if (delta < 0) == (r["paper_side"] == "<") else "contradicted") \
            if np.isfinite(delta) and delta != 0 else ""
        negl = seeds_tost(sd, delta, margin) if np.isfinite(margin) else math.nan
        options = [(n, o) for n, o in ((sided, sided_outcome), (negl, "negligible")) if np.isfinite(n)]
        if options:
            needed, outcome = min(options)
        elif (np.isfinite(sd) and sd > 0) and (sided == math.inf or negl == math.inf):
            needed, outcome = math.inf, "none within reach"
        else:
            needed, outcome = math.nan, "unknown"
        add = max(0.0, needed - n_now) if np.isfinite(needed) else needed
        hours = _hours(add, seed_cpu_s)
        note = ("no seed-to-seed s.d.: the claim could not be computed (or has one seed; the table's detail "
                "says why)" if not np.isfinite(sd)
                else "measured effect about 0 and no margin: no number of seeds decides it"
                if not options else "")
        rows.append(dict(
            claim_id=r["claim_id"], claim=r["claim"], verdict=r["verdict"], estimate=r["estimate"], null=r["null"],
            margin=margin, sd=sd, seeds_now=n_now, outcome=outcome,
            seeds_needed=needed if not np.isfinite(needed) else int(needed),
            cases_to_add=add if not np.isfinite(add) else int(add),
            config_seeds_to_add=int(math.ceil(add / ensembles)) if np.isfinite(add) else add,
            core_hours=hours, wall_hours_2_cores=wall_hours(hours, seed_cpu_s, 2),
            wall_hours_cluster=wall_hours(hours, seed_cpu_s, None), seeds_sided=sided, sided_outcome=sided_outcome,
            seeds_negligible=negl, note=note))
    return pd.DataFrame(rows, columns=COLUMNS)


def seed_cost(case_dirs, protocols) -> float:
    """Mean measured CPU seconds of one case: packing, pre-shear and one run of each protocol (NaN if unknown)."""
    cost = power.dem_cost(case_dirs, protocols)
    return float(cost["setup_cpu_s"] + len(protocols) * cost["transient_cpu_s"])


def build_parser():
    ap = argparse.ArgumentParser(prog="python -m claims plan",
                                 description="Seeds and core-hours that decide every undecided claim at 80 % power.")
    ap.add_argument("--table", required=True, help="the claims table, results/claims/paper_claims.csv")
    ap.add_argument("--dem", nargs="+", required=True, help="the campaign's DEM case directories (their stage costs)")
    ap.add_argument("--protocols", nargs="+", default=list(REVERSAL_PROTOCOLS),
                    help="the reversal protocols every new seed runs (default heaviside sinusoidal)")
    ap.add_argument("--out", required=True, help="the plan, e.g. results/claims/plan.csv")
    return ap


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        path = Path(args.table)
        if not path.is_file():
            raise DEMInputError(f"{path}: the claims table not found (run python -m claims first)")
        table = pd.read_csv(path, dtype={"claim_id": str})
        missing = [c for c in ("claim_id", "estimate", "null", "paper_side", "margin", "sd", "n", "verdict")
                   if c not in table.columns]
        if missing:
            raise DEMInputError(f"{path}: column(s) {', '.join(missing)} missing (a claims table of this version)")
        plan = plan_table(table, seed_cost(args.dem, args.protocols), ensembles_of(args.dem))
        out = Path(args.out)
        out.parent.mkdir(parents=True, exist_ok=True)
        plan.to_csv(out, index=False, float_format="%.6g")
    except (DEMInputError, ValueError) as exc:
        print(f"claims plan: error: {exc}", file=sys.stderr)
        return 2
    print(f"claims plan: {len(plan)} undecided claim(s) -> {out}")
    return 0
