"""What each step of the calibration returns (``calibrate.pipeline``): one frozen record per step.

Each step takes the ``problem.Problem`` and the records of the steps before it
that it needs, and returns its own; ``Calibration`` gathers them for the writers.
A route's record holds its fitted blocks (``fits.FitResult``, by block name) and
its full parameter document.
"""
from __future__ import annotations

from dataclasses import dataclass

import pandas as pd

#: The blocks of a parameter document a calibration fits.
BLOCKS = ("friction_eq2", "friction_quadratic", "model1", "model2")
MODELS = ("model1", "model2")


@dataclass(frozen=True)
class FrictionFit:
    """Step 3, the Eq. 2 fit: Eq. 2 and the quadratic law of [15] fitted to mu(X) (the tables' route ``mu_vs_X``).

    ``fits``: ``friction_eq2``, ``friction_quadratic`` -> ``fits.FitResult``.
    """

    fits: dict


@dataclass(frozen=True, eq=False)
class BacksolveFit:
    """Step 4, the back-solve: alpha(X) back-solved in bins of X, both models fitted to them (route ``backsolve``).

    Attributes
    ----------
    bins : DataFrame
        ``backsolve.binned``.
    fits : dict
        Every block of ``BLOCKS`` -> ``fits.FitResult`` (the friction laws are step 3's).
    doc : dict
        The full parameter document of the route (range-checked).
    """

    bins: pd.DataFrame
    fits: dict
    doc: dict

    @property
    def x_lower(self) -> float:
        """The lower bound of Model 1's X_c the route fitted under (``fits.xc_lower_bound`` with its bins)."""
        return self.fits["model1"].extra["X_c_lower_bound"]


@dataclass(frozen=True)
class CurvesFit:
    """Step 5, the curve fit: each model fitted to the DEM curves (the tables' route ``curves``).

    Attributes
    ----------
    fits : dict
        ``model1``, ``model2`` -> ``fits.FitResult``.
    doc : dict
        The back-solve's document with the curves route's model blocks.
    x_lower : float
        The lower bound of Model 1's X_c the fit ran under (``fits.xc_lower_bound``).
    """

    fits: dict
    doc: dict
    x_lower: float


@dataclass(frozen=True, eq=False)
class FreeformBound:
    """Step 5b, the free-form bound: alpha1(X), alpha2(X) as penalised splines (``freeform``).

    Attributes
    ----------
    table : DataFrame
        ``freeform.csv`` (one note row when the fit was not asked for or cannot run).
    curves : dict or None
        The curves of Figs. 3a, 3b (``freeform.curves_for_figure``); None without a fit.
    quality : tuple of dict
        Its ``fit_quality.csv`` row (shear stability); empty without a fit.
    """

    table: pd.DataFrame
    curves: dict | None = None
    quality: tuple = ()


@dataclass(frozen=True, eq=False)
class Bootstrap:
    """Step 6, the bootstrap over seeds (``bootstrap.run``).

    Attributes
    ----------
    values : DataFrame
        One row per (replicate, route, block, parameter).
    heldout : DataFrame
        One row per (replicate, route, model): the held-out scores.
    intervals : DataFrame
        ``bootstrap.intervals`` of ``values`` (empty, with its columns, when no replicate succeeded).
    """

    values: pd.DataFrame
    heldout: pd.DataFrame
    intervals: pd.DataFrame


@dataclass(frozen=True, eq=False)
class Identifiability:
    """Step 6b, what the data determine: profiles of the curves fit's objective, the sensitivity SVD, the verdict.

    Attributes
    ----------
    profiles : DataFrame
        ``profiles.profile`` rows of both models (``profiles.csv``).
    intervals : DataFrame
        ``profiles.intervals`` of ``profiles``.
    svd, verdict : DataFrame
        ``identifiability.svd_table`` and ``identifiability.verdict`` of both models
        (``sensitivity_svd.csv``, ``identifiability.csv``).
    """

    profiles: pd.DataFrame
    intervals: pd.DataFrame
    svd: pd.DataFrame
    verdict: pd.DataFrame


@dataclass(frozen=True)
class RouteChoice:
    """Step 7, each model's route and why (``route_choice.choose``).

    Attributes
    ----------
    quality : tuple of dict
        The ``fit_quality.csv`` rows of both routes of each model and of the friction laws.
    default_route : dict
        Block -> the route written to params.yaml.
    params : dict
        The parameter document of each model's default route (friction laws from the back-solve's).
    """

    quality: tuple
    default_route: dict
    params: dict


@dataclass(frozen=True, eq=False)
class Tables:
    """Step 8, the tables: params.yaml's document, ``params_table.csv`` and ``backsolve_alpha_vs_X.csv``.

    Attributes
    ----------
    params : dict
        The default routes' document with its ``intervals`` and ``provenance`` blocks.
    params_table : DataFrame
        Every route's values with intervals, defaults and constraint notes (``tables.params_table``).
    bins : DataFrame
        The back-solve's bins with their bootstrap intervals (``tables.bins_table``).
    """

    params: dict
    params_table: pd.DataFrame
    bins: pd.DataFrame


@dataclass(frozen=True, eq=False)
class Calibration:
    """Every step's record of one calibration: what ``pipeline.write_tables`` and ``write_figures`` write.

    ``intervals`` is step 6c's: the reported interval of every parameter (``pipeline.reported_intervals``).
    """

    backsolve: BacksolveFit
    curves: CurvesFit
    freeform: FreeformBound
    bootstrap: Bootstrap
    identifiability: Identifiability
    intervals: pd.DataFrame
    choice: RouteChoice
    tables: Tables
