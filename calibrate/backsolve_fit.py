r"""The back-solve route (the tables' ``backsolve``, once "route 1"): Eq. 4 back-solved, the laws fitted.

The models are fitted to alpha(X) back-solved from the smoothed DEM fabric
(``backsolve.binned``, Eq. 4), the friction laws to the samples' mu(X) (the
tables' ``mu_vs_X``: Eq. 2 and the quadratic law of [15]); ``fit_blocks`` chains
both through the fits of ``fits``. No integration of the model is needed, so the
bootstrap over seeds repeats it cheaply.
"""
from __future__ import annotations

import numpy as np

from . import backsolve, fits


def friction_data(samples, settings):
    """X and signed friction g sigma_xy/p of the samples where X is defined.

    The rate rule of the back-solve applies (X = A:D'/|D'| needs a rate), its
    skip after a reversal does not: the friction law needs no derivative, and
    the samples just after a reversal are the only ones at the largest X, where
    Eq. 2's fifth-order branch would otherwise be extrapolated (k5 ran to 8e6
    on the last bins before X ~ 0.06 without them).
    """
    keep = samples["rate_frac"].to_numpy() >= settings.rate_min
    d = samples[keep]
    X = d["X"].to_numpy()
    mu = (d["sigma_xy_over_p"] * d["g"]).to_numpy()
    return X, mu


def mu_noise(samples):
    """Per-sample friction noise: scatter of g sigma_xy/p about its strain-local mean (first differences)."""
    sig = []
    for _, d in samples.groupby(["case", "protocol", "piece"]):
        v = (d["sigma_xy_over_p"] * d["g"]).to_numpy()
        if len(v) > 3:
            sig.append(np.diff(v) / np.sqrt(2.0))
    s = np.concatenate(sig) if sig else np.array([0.04])
    return max(float(1.4826 * np.median(np.abs(s - np.median(s)))), 1e-4)


def fit_friction(samples, steady, sigma_mu: float, settings: backsolve.BacksolveSettings,
                 steady_weight: float) -> dict:
    """Fit Eq. 2 and the quadratic law of [15] to the samples' mu(X), each sample weighted by ``sigma_mu``.

    Returns
    -------
    dict
        ``friction_eq2``, ``friction_quadratic`` (``fits.FitResult``).
    """
    X, mu = friction_data(samples, settings)
    return {"friction_eq2": fits.fit_eq2(X, mu, sigma_mu, steady, steady_weight),
            "friction_quadratic": fits.fit_quadratic(X, mu, sigma_mu, steady, steady_weight)}


def fit_coefficients(samples, steady, settings: backsolve.BacksolveSettings, steady_weight: float, xc_margin: float,
                     model1_start=None) -> dict:
    """Back-solve alpha1, alpha2 in bins of X and fit Model 1 (Eq. 6) and Model 2 (Eq. 5) to them.

    Returns
    -------
    dict
        ``bins`` (DataFrame of ``backsolve.binned``), ``model1``, ``model2`` (``fits.FitResult``).
    """
    bins = backsolve.binned(samples, settings)
    return {"bins": bins,
            "model1": fits.fit_model1(bins, steady, steady_weight, xc_margin, x0=model1_start),
            "model2": fits.fit_model2(bins, steady, steady_weight)}


def fit_blocks(samples, steady, settings: backsolve.BacksolveSettings, steady_weight: float, xc_margin: float,
               model1_start=None) -> dict:
    """Back-solve and fit every block: ``fit_friction`` and ``fit_coefficients`` together.

    Returns
    -------
    dict
        ``bins`` (DataFrame), ``friction_eq2``, ``friction_quadratic``, ``model1``,
        ``model2`` (``fits.FitResult``), ``sigma_mu`` (the samples' friction noise, ``mu_noise``).
    """
    sigma_mu = mu_noise(samples)
    out = {"sigma_mu": sigma_mu, **fit_friction(samples, steady, sigma_mu, settings, steady_weight)}
    out.update(fit_coefficients(samples, steady, settings, steady_weight, xc_margin, model1_start))
    return out
