r"""The reversal design: which way of collecting reversals tells most about claim 4 per core-hour.

Claim 4's unit is the seed: a seed's value is the mean, over its reversals scored
out of sample, of the paired difference of squared model errors

.. math:: d = \mathrm{MSE}_{M1} - \mathrm{MSE}_{M2}

of :math:`|A|` over the first ``table.EARLY_A`` strain after the reversal
(``table.early_scores``; the DEM's noise floor cancels from it, ``claims.ensemble``).
A campaign that runs several reversal
protocols per seed (a single reversal, a train of reversals spaced 0.3 strain,
one spaced 0.5, ...) measures every design on the same seeds. For each protocol
:math:`p` this module computes, over the seeds:

- :math:`\bar d_{s,p}`, seed :math:`s`'s mean over the reversals of :math:`p`;
- :math:`\mathrm{sd}_p`, the s.d. of :math:`\bar d_{s,p}` over seeds (``ddof=1``),
  with its 90 % chi-square interval (the table's level), and the mean with its 90 % t interval;
- :math:`c_p`, the CPU hours of one seed of that design alone: packing,
  pre-shear and the run of :math:`p` (the stage sidecars' ``cpu_time_s``);
- the information per core-hour

  .. math:: \mathcal I_p = \frac{1}{\mathrm{sd}_p^2\, c_p},

  the inverse of the core-hours that bring the standard error of claim 4's mean
  to 1 (the seeds a claim needs scale as :math:`\mathrm{sd}^2`): the larger,
  the better the design;
- the design effect :math:`\mathrm{sd}_p^2 / (\mathrm{sd}_{1,p}^2 / k_p)` with
  :math:`\mathrm{sd}_{1,p}` the s.d. of single reversals and :math:`k_p` the
  reversals per seed (1: the reversals of a seed are as good as independent
  ones; :math:`k_p`: they repeat one another);
- how far the fabric has recovered when each reversal starts: the mean over
  reversals of :math:`|A_0|/|A|_{ss}`, :math:`A_0` the fabric just before the
  reversal (``claims.inputs.DemCase.initial_A``, from ``dem_contract.split_transients``:
  over the last ``PRE_REVERSAL_WINDOW`` strain of the leg before it) and :math:`|A|_{ss}` the
  pre-shear's steady :math:`|A|` (a train spaced too closely starts its later
  reversals from a fabric that has not regrown: a ratio below 1).

A branching design (one long pre-shear, saved states every :math:`\Delta`
strain, a single reversal of length :math:`L` from each) costs
:math:`\Delta + L` strain per reversal where a train spaced :math:`\Delta`
costs :math:`\Delta`; it can only win if the train's reversals start from an
unrecovered fabric or repeat one another, which the last two columns measure.
"""
from __future__ import annotations

import math
import re

import numpy as np
import pandas as pd
from scipy import stats

from . import power, table
from .stats import LEVEL

COLUMNS = ["protocol", "seeds", "reversals_per_seed", "mean_difference", "mean_lo", "mean_hi", "sd_per_seed",
           "sd_lo", "sd_hi", "sd_single_reversal", "design_effect", "cpu_hours_per_seed",
           "information_per_core_hour", "relative_information", "A_at_reversal_over_steady"]

_REVERSAL_SUFFIX = re.compile(r"_r\d+$")


def base_protocol(key: str) -> str:
    """The protocol of a comparison key: ``train03_r2`` (a schedule's second reversal) -> ``train03``."""
    return _REVERSAL_SUFFIX.sub("", str(key))


def sd_interval(sd: float, n: int, level: float = LEVEL) -> tuple:
    r"""Chi-square interval of a standard deviation from ``n`` values: :math:`s\sqrt{(n-1)/\chi^2_{q}}`."""
    if n < 2 or not np.isfinite(sd):
        return math.nan, math.nan
    a = (1.0 - level) / 2.0
    return (sd * math.sqrt((n - 1) / stats.chi2.ppf(1 - a, n - 1)),
            sd * math.sqrt((n - 1) / stats.chi2.ppf(a, n - 1)))


def recovery(dem_cases, protocol: str) -> float:
    r"""Mean :math:`|A_0|/|A|_{ss}` over the reversals of ``protocol`` in every case (module docstring); NaN if none.

    ``dem_cases``: ``claims.inputs.DemCase`` of each case (its ``initial_A`` and steady ``A_norm``).
    """
    ratios = [a / c.steady["A_norm"] for c in dem_cases for a in c.initial_A.get(protocol, [])]
    return float(np.mean(ratios)) if ratios else math.nan


def design_table(runs: dict, case_dirs, protocols, dem_cases=()) -> pd.DataFrame:
    """One row per reversal protocol (``COLUMNS``), from the claims' runs and the DEM cases' sidecars.

    Parameters
    ----------
    runs : dict
        ``claims.inputs.runs`` of the comparison's curves.
    case_dirs : list of path
        The DEM cases (stage sidecars: CPU time per stage).
    protocols : list of str
        The campaign's reversal protocols.
    dem_cases : sequence of claims.inputs.DemCase
        The same cases as read for the claims table (the fabric before each reversal); none: NaN recovery.
    """
    rows = []
    dem = table.dem_of(runs)
    for p in protocols:
        sub = {k: v for k, v in runs.items() if base_protocol(k[3]) == p}
        scores, _ = table.early_scores(sub, dem, "A_norm", table.EARLY_A)
        per_case = {}
        for r in scores:
            per_case.setdefault(r["key"][1], []).append(r["mse"]["model1"] - r["mse"]["model2"])
        _, v = table.per_seed(per_case)
        single = np.array([x for vals in per_case.values() for x in vals], float)
        single = single[np.isfinite(single)]
        k = single.size / v.size if v.size else math.nan
        sd = float(np.std(v, ddof=1)) if v.size >= 2 else math.nan
        sd1 = float(np.std(single, ddof=1)) if single.size >= 2 else math.nan
        lo, hi = sd_interval(sd, v.size)
        mean = float(v.mean()) if v.size else math.nan
        half = (stats.t.ppf(0.5 + LEVEL / 2, v.size - 1) * sd / math.sqrt(v.size)) if v.size >= 2 else math.nan
        cost = power.dem_cost(case_dirs, [p])
        hours = (cost["setup_cpu_s"] + cost["transient_cpu_s"]) / 3600.0
        rows.append(dict(
            protocol=p, seeds=int(v.size), reversals_per_seed=k, mean_difference=mean, mean_lo=mean - half,
            mean_hi=mean + half, sd_per_seed=sd, sd_lo=lo, sd_hi=hi, sd_single_reversal=sd1,
            design_effect=sd ** 2 / (sd1 ** 2 / k) if v.size and sd1 > 0 else math.nan,
            cpu_hours_per_seed=hours, information_per_core_hour=1.0 / (sd ** 2 * hours) if sd > 0 else math.nan,
            A_at_reversal_over_steady=recovery(dem_cases, p)))
    out = pd.DataFrame(rows, columns=COLUMNS)
    best = out["information_per_core_hour"].max()
    out["relative_information"] = out["information_per_core_hour"] / best if np.isfinite(best) else math.nan
    return out
