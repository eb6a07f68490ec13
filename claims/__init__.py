r"""The paper's claims, decided with statistics: ``results/claims/paper_claims.csv`` and its figure.

One row per claim of the paper, and per figure for the model comparisons of
claims 4, 7 and 9 (step reversals: Fig. 4; the sinusoidal reversal: Fig. 5;
a pooled row as a secondary line): its statistic, 90 % interval, test, n,
adequacy and verdict, computed from the comparison's per-seed curves
(``results/compare/<set>/predictions.csv`` and ``errors.csv``, and the
pole-at-start variant's) and the DEM series (through ``dem_contract``).

Decision rule (``stats.verdict``, one level: one-sided tests at 5 %, the 90 %
interval): a claim is **reproduced** if the interval lies strictly on the
paper's side of the null value (no effect), **contradicted** if strictly on
the other side, **negligible** if it lies inside null +- its margin
(``margins``: the smallest effect that matters; with one of the first two:
"reproduced, negligible"), **inconclusive** otherwise; **both fail** where the
two models compared both lie outside the DEM's ensemble band. "theta_A always
passes through 90 degrees" is contradicted by a run crossing the horizontal
at family-wise 5 % over the runs (Holm). Model comparisons are scored on the
model error, not the DEM's noise (``ensemble``), out of sample and paired on
each run (``table`` module docstring).

Modules: ``stats`` (intervals, Holm, the rule), ``ensemble`` (the DEM's noise
floor and the scatter of its crossings), ``margins`` (the margin of every
comparative claim, the pooled rows' weights), ``measures`` (per-run
quantities), ``inputs`` (what is read), ``table`` (the rows), ``power`` (seeds
and DEM volume that decide each comparison row: ``power.csv``), ``plan`` (every
undecided row), ``design`` (the reversal design), ``pole_start`` (the paper's
configuration of Model 1), ``report`` (forest plot, Markdown section), ``cli``
(``python -m claims``).
"""
from .stats import clopper_pearson, mean_interval, verdict
from .table import COLUMNS, claims_table

__all__ = ["COLUMNS", "claims_table", "clopper_pearson", "mean_interval", "verdict"]
