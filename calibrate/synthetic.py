r"""Synthetic DEM cases made by ``model/``: test data in exactly the DEM layout.

The calibration is tested on time series that ``model.simulate`` generates from
known parameters, with Gaussian noise of the magnitude DESIGN.md measured on
one 500-disk run (0.04 in mu, 0.01-0.015 in each fabric component per sample),
written as ``preshear.csv``, ``heaviside.csv``, ``sinusoidal.csv`` (+ JSON
sidecars) with every contract column filled consistently. Nothing here is a
stand-in for the DEM: it is the known truth the round-trip tests compare with.

Conventions (dimensionless, DESIGN.md): stresses in p (so ``p = 1``), lengths in
d, times in d sqrt(rho/p); then ``gammadot = I`` (the inertial number).
Sampling follows DESIGN.md: every ``fine`` strain in the first ``fine_window``
after a reversal, every ``coarse`` elsewhere.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from model import sinusoidal, simulate, steady_shear

from .io import CONTRACT_COLUMNS

FABRIC_NOISE = 0.0125   # per sample, one 500-disk run (DESIGN.md: 0.01-0.015)
MU_NOISE = 0.04         # per sample, one 500-disk run (DESIGN.md)


def _grid(total, fine, fine_window, coarse):
    a = np.arange(0.0, min(fine_window, total) + 1e-12, fine)
    b = np.arange(a[-1] + coarse, total + 1e-12, coarse)
    g = np.concatenate([a, b])
    if g[-1] < total - 1e-9:
        g = np.append(g, total)
    return g


def _table(sim, rng, I, fabric_noise, mu_noise, strain0, t0):
    n = len(sim)
    gd = sim["gammadot"].to_numpy() * I
    a = sim["A_xx"].to_numpy() + rng.normal(0.0, fabric_noise, n)
    b = sim["A_xy"].to_numpy() + rng.normal(0.0, fabric_noise, n)
    sig = sim["sigma_xy_over_p"].to_numpy() + rng.normal(0.0, mu_noise, n)
    gap = 37.0 + rng.normal(0.0, 0.01, n)
    df = pd.DataFrame({
        "t": t0 + sim["t"].to_numpy() / I,
        "strain": strain0 + sim["strain"].to_numpy(),
        "gammadot": gd,
        "U_top": 0.5 * gd * gap, "U_bottom": -0.5 * gd * gap, "gap": gap,
        "A_xx": a, "A_xy": b, "n_contacts": np.full(n, 1000),
        "sigma_xy": sig, "p": np.ones(n), "mu": np.abs(sig),
        "sigma_xy_bulk": sig + rng.normal(0.0, mu_noise, n), "p_bulk": 1.0 + rng.normal(0.0, 0.01, n),
        "phi": np.full(n, 0.81), "Z": np.full(n, 3.6), "inertial_number": np.abs(gd),
    }, columns=list(CONTRACT_COLUMNS))
    return df


def write_case(case_dir, params, seed, model="model1", friction="eq2", I=1e-3,
               preshear_strain=3.0, heaviside_strain=0.4, sinusoidal_strain=0.4, transition_strain=0.1,
               fabric_noise=FABRIC_NOISE, mu_noise=MU_NOISE, fine=0.001, fine_window=0.1, coarse=0.01,
               A_start=(0.0, 0.0), protocols=("heaviside", "sinusoidal")):
    """Write one synthetic case directory (pre-shear from ``A_start``, then the reversals).

    Returns the directory path. ``seed`` seeds the noise; ``params`` is anything
    ``model.simulate`` accepts.
    """
    case_dir = Path(case_dir)
    case_dir.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    kw = dict(model=model, friction=friction, rtol=1e-9, atol=1e-12)
    s_pre = _grid(preshear_strain, coarse, 0.0, coarse)
    pre = simulate(params, steady_shear(preshear_strain), A0=A_start, strain_eval=s_pre, **kw)
    A_end = (float(pre["A_xx"].iloc[-1]), float(pre["A_xy"].iloc[-1]))
    df = _table(pre, rng, I, fabric_noise, mu_noise, 0.0, 0.0)
    out = {"preshear": df}
    t_end = float(df["t"].iloc[-1])
    if "heaviside" in protocols:
        s = _grid(heaviside_strain, fine, fine_window, coarse)
        sim = simulate(params, steady_shear(heaviside_strain, -1.0), A0=A_end, strain_eval=-s, **kw)
        out["heaviside"] = _table(sim, rng, I, fabric_noise, mu_noise, preshear_strain, t_end)
    if "sinusoidal" in protocols:
        h = sinusoidal(0.0, transition_strain, sinusoidal_strain)
        # time sampling: fine steps of strain-at-full-rate during the transition and fine window
        T = h.t_end
        t_fine_end = transition_strain + fine_window
        t = np.concatenate([np.arange(0.0, t_fine_end, fine), np.arange(t_fine_end, T, coarse), [T]])
        t = np.unique(np.round(t, 12))
        sim = simulate(params, h, A0=A_end, t_eval=t, **kw)
        out["sinusoidal"] = _table(sim, rng, I, fabric_noise, mu_noise, preshear_strain, t_end)
    for name, table in out.items():
        table.to_csv(case_dir / f"{name}.csv", index=False)
        meta = {"synthetic": True, "generator": "calibrate.synthetic.write_case", "model": model,
                "noise_seed": int(seed), "fabric_noise": fabric_noise, "mu_noise": mu_noise,
                "inertial_number": I, "protocol": name}
        (case_dir / f"{name}.json").write_text(json.dumps(meta, indent=1))
    return case_dir


def write_ensemble(root, params, seeds=(1, 2, 3, 4), group="p1_I0.001", **kw):
    """Write one case per seed, named ``<group>_s<seed>``; return their paths."""
    root = Path(root)
    return [write_case(root / f"{group}_s{s}", params, seed=s, **kw) for s in seeds]
