r"""The paper's claims, decided with statistics: ``results/claims/paper_claims.csv`` and its figure.

One row per claim of the paper (its statistic, 95 % interval, test, n and a
verdict), computed from the comparison's per-seed curves
(``results/compare/<set>/predictions.csv`` and ``errors.csv``) and the DEM
series (through ``dem_contract``).

Decision rule (``stats.verdict``): a claim is **reproduced** if the 95 %
interval of its statistic lies strictly on the paper's side of the null value
(no effect), **contradicted** if strictly on the other side, **negligible** if
its 90 % equivalence interval (two one-sided tests at 5 %) lies inside null +-
its margin (``margins``: the smallest effect that matters; with one of the
first two: "reproduced, negligible"), **inconclusive** otherwise (the interval
contains the null, or there are too few seeds to compute one). "theta_A always
passes through 90 degrees" (the sign of A_xx where A_xy changes sign, per seed;
``dem_contract.passage``, the rule the comparison reports too) is also
contradicted by a single DEM run that clearly crosses the horizontal. Intervals are over
seeds pooled across ensembles; model comparisons are out of sample and paired
on each run (``table`` module docstring).

Modules: ``stats`` (bootstrap, equivalence interval, Clopper-Pearson, the rule), ``margins``
(the margin of every comparative claim), ``measures``
(per-run quantities), ``inputs`` (what is read), ``table`` (the rows),
``power`` (seeds and DEM volume that decide claims 4 and 7: ``power.csv``),
``report`` (forest plot, Markdown section), ``cli`` (``python -m claims``).
"""
from .stats import clopper_pearson, mean_interval, verdict
from .table import COLUMNS, claims_table

__all__ = ["COLUMNS", "claims_table", "clopper_pearson", "mean_interval", "verdict"]
