r"""DEM-like cases made by ``model/``, in exactly the DEM contract layout.

For tests and trial runs of the analysis stages while no DEM output exists:
one case directory per seed with ``preshear.csv``, ``heaviside.csv``,
``sinusoidal.csv`` and JSON sidecars, every contract column filled
consistently. Nothing here stands in for the DEM in the pipeline; it is the
known truth the calibration and the comparison are checked against
(``calibrate.synthetic`` sets the calibration tests' defaults; ``python -m
compare synthetic`` writes cases from the command line).

Conventions (dimensionless, docs/data-contract.md): stresses in p (``p = 1``), lengths in
d, times in d sqrt(rho/p), so the rate equals the inertial number ``I``.
Sampling follows the DEM's (docs/data-contract.md): every ``fine`` strain in the first ``fine_window``
after the start of a stage (after the end of the transition for the
sinusoidal reversal), every ``coarse`` elsewhere.

- The pre-shear starts from ``A_start``: the model's steady state (default,
  so the fabric before the reversal is known exactly), or a given fabric such
  as isotropy ``(0, 0)`` (then the transient to steady state is in the data).
- Each reversal starts from the pre-shear's last fabric and is integrated on
  ``model.tabulated`` histories sampled at the output times (the imposed
  history *is* the table), so a consumer that integrates the same model from
  the same fabric on that table reproduces the series to the integrator's
  tolerance. The sidecars of the reversal runs carry ``reversal_t`` and
  ``reversal_strain`` (docs/data-contract.md).
- Noise (``fabric_noise``, ``mu_noise``; the magnitude measured for one
  500-disk run is ``FABRIC_NOISE``, ``MU_NOISE``) is Gaussian per sample on
  A_xx, A_xy and sigma_xy. With noise the cell also breathes: the gap
  fluctuates by ``GAP_NOISE`` d (so the measured rate, walls over gap,
  fluctuates too), sigma_xy_bulk has its own noise of ``mu_noise`` and p_bulk
  of 0.01 p. Where the walls stand still, mu is the model's (friction law at
  X), not |sigma_xy|/p = 0.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from model import simulate, sinusoidal, steady_shear, tabulated

from .series import CONTRACT_COLUMNS, REVERSAL_PROTOCOLS

FABRIC_NOISE = 0.0125   # per sample and fabric component, one 500-disk run (docs/data-contract.md: 0.01-0.015)
MU_NOISE = 0.04         # per sample in mu, one 500-disk run (docs/data-contract.md)
GAP = 37.0              # mean gap between the walls, d
GAP_NOISE = 0.01        # d


def strain_grid(total, fine, fine_window, coarse):
    """Strains 0..total: every ``fine`` up to ``fine_window``, then every ``coarse``; ``total`` included."""
    a = np.arange(0.0, min(fine_window, total) + 1e-12, fine)
    b = np.arange(a[-1] + coarse, total + 1e-12, coarse)
    g = np.concatenate([a, b])
    return g if g[-1] >= total - 1e-9 else np.append(g, total)


def _table(sim, rng, I, fabric_noise, mu_noise, strain0, t0):
    """One run of ``model.simulate`` as a contract table, with noise (draw order fixed: the tests' realizations)."""
    n = len(sim)
    a = sim["A_xx"].to_numpy() + rng.normal(0.0, fabric_noise, n)
    b = sim["A_xy"].to_numpy() + rng.normal(0.0, fabric_noise, n)
    sig = sim["sigma_xy_over_p"].to_numpy() + rng.normal(0.0, mu_noise, n)
    noisy = bool(fabric_noise or mu_noise)
    gap = GAP + (rng.normal(0.0, GAP_NOISE, n) if noisy else 0.0)
    sig_bulk = sig + (rng.normal(0.0, mu_noise, n) if noisy else 0.0)
    p_bulk = np.ones(n) + (rng.normal(0.0, 0.01, n) if noisy else 0.0)
    U = 0.5 * sim["gammadot"].to_numpy() * I * GAP   # the walls impose the rate over the mean gap
    gd = 2 * U / gap                                  # the rate as measured: walls over the actual gap
    mu = np.where(sim["gammadot"].to_numpy() == 0.0, sim["mu"].to_numpy(), np.abs(sig))
    return pd.DataFrame({
        "t": t0 + sim["t"].to_numpy() / I, "strain": strain0 + sim["strain"].to_numpy(), "gammadot": gd,
        "U_top": U, "U_bottom": -U, "gap": gap, "A_xx": a, "A_xy": b, "n_contacts": np.full(n, 1000),
        "sigma_xy": sig, "p": np.ones(n), "mu": mu, "sigma_xy_bulk": sig_bulk, "p_bulk": p_bulk,
        "phi": np.full(n, 0.81), "Z": np.full(n, 3.6), "inertial_number": np.abs(gd),
    }, columns=list(CONTRACT_COLUMNS))


def write_case(case_dir, params, seed=1, model="model1", friction="eq2", I=1e-3, preshear_strain=1.0,
               reversal_strain=0.5, transition_strain=0.1, fabric_noise=0.0, mu_noise=0.0,
               fine=0.001, fine_window=0.1, coarse=0.01, A_start=None, protocols=REVERSAL_PROTOCOLS,
               schedules=None):
    """Write one synthetic case directory and return its path.

    Parameters
    ----------
    case_dir : str or Path
        Created if needed; name it ``p<P>_I<I>_s<seed>`` to form ensembles.
    params
        Anything ``model.simulate`` accepts.
    seed : int
        Seeds the noise.
    model, friction : str
        Passed to ``model.simulate``.
    I : float
        Inertial number (= the rate in these units).
    preshear_strain, reversal_strain, transition_strain : float
        Length of the pre-shear, of each reversal run (the sinusoidal one
        includes its half-cosine transition of ``transition_strain``).
    fabric_noise, mu_noise : float
        Per-sample Gaussian noise (module docstring); 0 for exact series.
    fine, fine_window, coarse : float
        Sampling (module docstring).
    A_start : (float, float), optional
        Fabric at the start of the pre-shear; default the model's steady state.
    protocols : sequence of {"heaviside", "sinusoidal"}
        The reversal runs to write after the pre-shear.
    schedules : dict, optional
        Reversal schedules to write too, name -> list of (strain, direction) segments
        with sharp reversals, or (strain, direction, transition_strain) for a reversal
        through a half cosine within the segment's strain (direction relative to the
        pre-shear, as in docs/scene.md):
        one run each, whose sidecar lists every reversal (``reversals``), sampled as
        the DEM samples it (a row at each reversal inside the run, the state just
        before it, then fine sampling again).
    """
    case_dir = Path(case_dir)
    case_dir.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    kw = dict(model=model, friction=friction)
    pre = simulate(params, steady_shear(preshear_strain), A0=A_start,
                   strain_eval=strain_grid(preshear_strain, coarse, 0.0, coarse), **kw)
    A_end = (float(pre["A_xx"].iloc[-1]), float(pre["A_xy"].iloc[-1]))
    out = {"preshear": _table(pre, rng, I, fabric_noise, mu_noise, 0.0, 0.0)}
    t_end = float(out["preshear"]["t"].iloc[-1])
    for protocol in protocols:
        if protocol == "heaviside":
            t = strain_grid(reversal_strain, fine, fine_window, coarse)
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
        out[protocol] = _table(sim, rng, I, fabric_noise, mu_noise, preshear_strain, t_end)
    reversals = {}
    for name, segs in (schedules or {}).items():
        out[name], reversals[name] = _schedule_run(params, segs, A_end, rng, I, fabric_noise, mu_noise,
                                                   preshear_strain, t_end, fine, fine_window, coarse, kw)
    for name, table in out.items():
        table.to_csv(case_dir / f"{name}.csv", index=False)
        meta = {"synthetic": True, "generator": "dem_contract.synthetic.write_case", "model": model,
                "friction": friction, "noise_seed": int(seed), "fabric_noise": fabric_noise,
                "mu_noise": mu_noise, "inertial_number": I, "stage": name}
        if name in reversals:    # a schedule: every reversal, the first also as reversal_t, reversal_strain
            meta.update(reversal_t=reversals[name][0]["t"], reversal_strain=reversals[name][0]["strain"],
                        reversals=reversals[name])
        elif name != "preshear":   # as docs/data-contract.md: the start of the reversal
            meta.update(reversal_t=t_end, reversal_strain=float(preshear_strain))
        (case_dir / f"{name}.json").write_text(json.dumps(meta, indent=1))
    return case_dir


def _schedule_run(params, segs, A_end, rng, I, fabric_noise, mu_noise, strain0, t0, fine, fine_window, coarse, kw):
    """One schedule's run: each segment integrated from the previous one's last fabric at a constant rate.

    Returns the contract table and the sidecar's reversal list.
    """
    parts, rev, A, t_at, s_at, prev = [], [], A_end, 0.0, 0.0, 1
    for k, (length, direction, *half_cosine) in enumerate(segs):
        if half_cosine and direction != prev:   # the rate turns from prev to direction through a half cosine
            ts = float(half_cosine[0])
            h = sinusoidal(0.0, ts, length - ts)
            t_fine = ts + fine_window
            t = np.unique(np.round(np.concatenate(
                [np.arange(0.0, t_fine, fine), np.arange(t_fine, h.t_end, coarse), [h.t_end]]), 12))
            g = prev * h.gammadot(t)
        else:
            t = strain_grid(length, fine, fine_window, coarse)
            g = np.full_like(t, float(direction))
        sim = simulate(params, tabulated(t, g), A0=A, t_eval=t, **kw)
        A = (float(sim["A_xx"].iloc[-1]), float(sim["A_xy"].iloc[-1]))
        if direction != prev:
            rev.append({"t": t0 + t_at / I, "strain": strain0 + s_at, "direction": int(direction),
                        "transition": "half_cosine" if half_cosine else "heaviside"}
                       | ({"transition_strain": float(half_cosine[0])} if half_cosine else {}))
        sim = sim.assign(t=sim["t"] + t_at, strain=sim["strain"] + s_at)
        parts.append(sim if k == 0 else sim.iloc[1:])   # the segment's first row is the previous one's last
        t_at, s_at, prev = t_at + length, s_at + float(sim["strain"].iloc[-1] - sim["strain"].iloc[0]), direction
    return _table(pd.concat(parts, ignore_index=True), rng, I, fabric_noise, mu_noise, strain0, t0), rev


def write_ensemble(root, params, seeds=(1, 2, 3, 4), group="p1_I0.001", **kw):
    """One case per seed, named ``<group>_s<seed>`` under ``root`` (options of ``write_case``); returns their paths."""
    root = Path(root)
    return [write_case(root / f"{group}_s{s}", params, seed=s, **kw) for s in seeds]
