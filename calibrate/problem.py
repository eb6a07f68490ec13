"""The calibration problem: the DEM runs as every step reads them, their noise and the settings, built once.

``pose`` is steps 1 and 2 of ``pipeline.run``: read the case directories
(``io.read_cases``), smooth their runs (``smoothing.smooth_cases``), take the
ensemble's steady state (``io.steady_values``), prepare the runs as the curves
route replays them (``dem_replays.prepare``) and the friction noise every fit
weighs mu by (``backsolve_fit.mu_noise``). Every later step reads the ``Problem``
and never changes it.
"""
from __future__ import annotations

from dataclasses import dataclass

import pandas as pd

from model import default_params

from . import backsolve_fit, dem_replays, io, smoothing
from .settings import Settings

#: Fewest seeds per ensemble for bootstrap intervals worth the name; below it the calibration warns.
MIN_SEEDS = 3


@dataclass(frozen=True, eq=False)   # eq=False: compared by identity (its tables and arrays have no one equality)
class Problem:
    """What the calibration fits, read and prepared once from its inputs (``pose``).

    Attributes
    ----------
    cases : tuple of io.Case
        The DEM case directories, read and checked (step 1).
    samples : DataFrame
        The smoothed samples of every run (``smoothing.smooth_cases``, step 2).
    steady : dict
        The ensemble steady state of the pre-shears (``io.steady_values``).
    replays : tuple of dem_replays.Replay
        The runs as the curves route integrates them.
    sigma_mu : float
        The noise of one friction sample (``backsolve_fit.mu_noise``): the scale of mu's residuals in every fit.
    base_doc : dict
        The model's default parameter document, without provenance: what no step fits.
    settings : Settings
        The settings of every step.
    warning : str
        Why the intervals may understate the uncertainty (``seed_warning``), "" if they need not.
    command : tuple of str or None
        The command line that posed the problem (params.yaml's provenance).
    """

    cases: tuple
    samples: pd.DataFrame
    steady: dict
    replays: tuple
    sigma_mu: float
    base_doc: dict
    settings: Settings
    warning: str = ""
    command: tuple | None = None


def pose(case_dirs, settings: Settings, command=None) -> Problem:
    """Steps 1 and 2, read and smooth: pose the ``Problem`` of ``case_dirs`` under ``settings`` (module Notes)."""
    cases = io.read_cases(case_dirs, settings.protocols, settings.min_samples)
    samples = smoothing.smooth_cases(cases, settings.smoothing)
    base_doc = default_params().to_dict()
    base_doc.pop("provenance", None)
    return Problem(cases=tuple(cases), samples=samples, steady=io.steady_values(cases),
                   replays=tuple(dem_replays.prepare(cases, samples, settings.backsolve)),
                   sigma_mu=backsolve_fit.mu_noise(samples), base_doc=base_doc, settings=settings,
                   warning=seed_warning(cases), command=tuple(command) if command else None)


def seed_warning(cases) -> str:
    """A warning when an ensemble has fewer than ``MIN_SEEDS`` seeds ("" otherwise).

    The bootstrap resamples seeds: with one seed every replicate is the same
    and the intervals have zero width; with two they take three values.
    """
    few = {g: n for g, n in sorted(seeds_per_ensemble(cases).items()) if n < MIN_SEEDS}
    if not few:
        return ""
    listed = ", ".join(f"{g} ({n} seed{'s' if n > 1 else ''})" for g, n in few.items())
    return (f"bootstrap intervals rest on fewer than {MIN_SEEDS} seeds per ensemble: {listed}; they understate "
            f"the uncertainty (zero width with one seed)")


def seeds_per_ensemble(cases) -> dict:
    """Ensemble (``io.Case.group``: one pressure and inertial number) -> its number of seeds (cases)."""
    counts = {}
    for c in cases:
        counts[c.group] = counts.get(c.group, 0) + 1
    return counts
