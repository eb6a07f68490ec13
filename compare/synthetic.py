r"""DEM-like time series made by ``model/``, in exactly the DEM contract layout.

For tests and trial runs while no DEM output exists: one case directory per
seed with ``preshear.csv``, ``heaviside.csv``, ``sinusoidal.csv`` and JSON
sidecars, every contract column filled. Nothing here stands in for the DEM in
the pipeline; it is the known truth the comparison is checked against.

Units as DESIGN.md: stresses in p (``p = 1``), lengths in d, times in
d sqrt(rho/p), so the rate equals the inertial number ``I``. The reversal runs
are generated on ``model.tabulated`` histories sampled at the output times (the
imposed history *is* the table), so a comparison that integrates the same model
from the same fabric must reproduce them to the integrator's tolerance.
Noise (optional) has DESIGN.md's magnitude for one 500-disk run: 0.0125 per
fabric component and 0.04 in mu per sample; the gap fluctuates by 0.01 d,
which makes the measured rate (walls over gap) fluctuate too.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from model import simulate, sinusoidal, steady_shear, tabulated

from .dem import CONTRACT_COLUMNS

FABRIC_NOISE = 0.0125
MU_NOISE = 0.04
GAP = 37.0


def _strain_grid(total, fine, fine_window, coarse):
    a = np.arange(0.0, min(fine_window, total) + 1e-12, fine)
    b = np.arange(a[-1] + coarse, total + 1e-12, coarse)
    g = np.concatenate([a, b])
    return g if g[-1] >= total - 1e-9 else np.append(g, total)


def _frame(sim, rng, I, fabric_noise, mu_noise, strain0, t0):
    n = len(sim)
    g_true = sim["gammadot"].to_numpy() * I
    gap = GAP + (rng.normal(0.0, 0.01, n) if fabric_noise or mu_noise else 0.0)
    U = 0.5 * g_true * GAP
    gd = 2 * U / gap
    a = sim["A_xx"].to_numpy() + rng.normal(0.0, fabric_noise, n)
    b = sim["A_xy"].to_numpy() + rng.normal(0.0, fabric_noise, n)
    sig = sim["sigma_xy_over_p"].to_numpy() + rng.normal(0.0, mu_noise, n)
    # where the walls stand still, mu is the model's (friction law at X), not |sigma|/p = 0
    mu = np.where(sim["gammadot"].to_numpy() == 0.0, sim["mu"].to_numpy(), np.abs(sig))
    return pd.DataFrame({
        "t": t0 + sim["t"].to_numpy() / I, "strain": strain0 + sim["strain"].to_numpy(), "gammadot": gd,
        "U_top": U, "U_bottom": -U, "gap": gap, "A_xx": a, "A_xy": b, "n_contacts": np.full(n, 1000),
        "sigma_xy": sig, "p": np.ones(n), "mu": mu, "sigma_xy_bulk": sig, "p_bulk": np.ones(n),
        "phi": np.full(n, 0.81), "Z": np.full(n, 3.6), "inertial_number": np.abs(gd),
    }, columns=list(CONTRACT_COLUMNS))


def write_case(case_dir, params, seed=1, model="model1", friction="eq2", I=1e-3, preshear_strain=1.0,
               reversal_strain=0.5, transition_strain=0.1, fabric_noise=0.0, mu_noise=0.0,
               fine=0.001, fine_window=0.1, coarse=0.01, protocols=("heaviside", "sinusoidal")):
    """Write one synthetic case directory and return its path.

    The pre-shear starts at the model's steady state (so the fabric before the
    reversal is known exactly); each reversal starts from the pre-shear's last
    fabric. ``seed`` seeds the noise.
    """
    case_dir = Path(case_dir)
    case_dir.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    kw = dict(model=model, friction=friction)
    pre = simulate(params, steady_shear(preshear_strain),
                   strain_eval=_strain_grid(preshear_strain, coarse, 0.0, coarse), **kw)
    A_end = (float(pre["A_xx"].iloc[-1]), float(pre["A_xy"].iloc[-1]))
    out = {"preshear": _frame(pre, rng, I, fabric_noise, mu_noise, 0.0, 0.0)}
    t_end = float(out["preshear"]["t"].iloc[-1])
    for protocol in protocols:
        if protocol == "heaviside":
            t = _strain_grid(reversal_strain, fine, fine_window, coarse)
            g = -np.ones_like(t)
        elif protocol == "sinusoidal":
            h = sinusoidal(0.0, transition_strain, reversal_strain)
            t_fine = transition_strain + fine_window
            t = np.unique(np.round(np.concatenate(
                [np.arange(0.0, t_fine, fine), np.arange(t_fine, h.t_end, coarse), [h.t_end]]), 12))
            g = h.gammadot(t)
        else:
            raise ValueError(f"protocol {protocol!r} is not heaviside or sinusoidal")
        sim = simulate(params, tabulated(t, g), A0=A_end, t_eval=t, **kw)
        out[protocol] = _frame(sim, rng, I, fabric_noise, mu_noise, preshear_strain, t_end)
    for name, frame in out.items():
        frame.to_csv(case_dir / f"{name}.csv", index=False)
        meta = {"synthetic": True, "generator": "compare.synthetic.write_case", "model": model,
                "friction": friction, "noise_seed": int(seed), "fabric_noise": fabric_noise,
                "mu_noise": mu_noise, "inertial_number": I, "stage": name}
        if name != "preshear":   # as yade_scripts/SCENE.md: the start of the reversal
            meta.update(reversal_t=t_end, reversal_strain=float(preshear_strain))
        (case_dir / f"{name}.json").write_text(json.dumps(meta, indent=1))
    return case_dir


def write_ensemble(root, params, seeds=(1, 2, 3, 4), group="p1_I0.001", **kw):
    """One case per seed, named ``<group>_s<seed>``; returns their paths."""
    root = Path(root)
    return [write_case(root / f"{group}_s{s}", params, seed=s, **kw) for s in seeds]
