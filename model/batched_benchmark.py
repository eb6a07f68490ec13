"""What the batched integrator saves: ``simulate_batch`` against a loop of ``simulate``.

``python -m model.batched_benchmark --out results/accuracy`` prints and writes
``batched_cost.csv``: for N = 1, 10, 100, 1000 Heaviside trajectories, the wall
time of one ``model.batched.simulate_batch`` call and of the loop of
``model.simulate`` (LSODA, rtol 1e-10, the default) over the same trajectories,
measured in the same run, their ratio, and the largest deviation between the two
in |A|, theta_A (deg) and mu over every report point of every trajectory.

Trajectories: a Heaviside reversal from a pre-reversal fabric A0 at a constant
rate (``steady_shear(3, -1)`` from A0, 601 report points, as ``compare`` and
route 2 of ``calibrate`` integrate a DEM run), with parameter sets drawn around a
calibrated set, half Model 1 (friction Eq. 2), half Model 2 (the quadratic law):
each coefficient times exp(0.05 z), z standard normal (seeded). A0 is the
steady state of the calibrated set (one per model), as a DEM run's pre-reversal
state is not exactly a trial set's own steady state. Eq. 2 and the quadratic law
are the defaults of ``model.params``.

For the first ``--reference`` trajectories (default 10) both integrators are
also compared with a Radau reference at rtol 1e-13 (columns ``ref_err_*``), which
says which of the two a deviation comes from.
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import pandas as pd

from .batched import simulate_batch
from .histories import steady_shear
from .integrate import simulate, steady_state
from .params import default_params, params_from_dict

CALIBRATED = {
    "model1": {"a1": -1.69, "b1": 32.0, "c1": -628.0, "a2": -56.9, "b2": -72.7, "c2": 8.5e4, "X_c": 0.242},
    "model2": {"c1": -1.64, "c2": -19.6, "c3": -14.0},
}
FRICTION = {"model1": "eq2", "model2": "quadratic"}
SIZES = (1, 10, 100, 1000)
SPREAD = 0.05          # relative spread of the sampled coefficients
STRAIN_AFTER = 3.0     # strain sheared after the reversal
QUANTITIES = ("A_norm", "theta_A", "mu")


def calibrated_params():
    doc = default_params().to_dict()
    doc.update({m: dict(v) for m, v in CALIBRATED.items()})
    return params_from_dict(doc, source="model.batched_benchmark.CALIBRATED")


def trajectories(n, seed=0):
    """``n`` (params, model, friction, A0) around the calibrated set, alternating Model 1 and Model 2."""
    rng = np.random.default_rng(seed)
    base = calibrated_params()
    a0 = {m: steady_state(base, m)[:2] for m in CALIBRATED}
    doc = base.to_dict()
    out = []
    for i in range(n):
        model = "model1" if i % 2 == 0 else "model2"
        d = dict(doc)
        d[model] = {k: v * float(np.exp(SPREAD * rng.standard_normal())) for k, v in CALIBRATED[model].items()}
        out.append((params_from_dict(d, source=f"benchmark trajectory {i}"), model, FRICTION[model], a0[model]))
    return out


def _deviation(a, b):
    return {q: float(np.max(np.abs(a[q].to_numpy() - b[q].to_numpy()))) for q in QUANTITIES}


def measure(n, history, reference=10, seed=0):
    """One row of the table: batched and looped wall time, ratio, deviations, statuses."""
    traj = trajectories(n, seed)
    P, M, F, A0 = (list(x) for x in zip(*traj))
    t0 = time.perf_counter()
    batch = simulate_batch(P, history, model=M, A0=A0, friction=F)
    t_batch = time.perf_counter() - t0
    loop, t0 = [], time.perf_counter()
    for p, m, f, a0 in traj:
        try:
            loop.append(simulate(p, history, model=m, A0=a0, friction=f))
        except (ValueError, FloatingPointError, RuntimeError) as exc:
            loop.append(exc)
    t_loop = time.perf_counter() - t0

    dev = dict.fromkeys(QUANTITIES, 0.0)
    agree = True
    for i, ref in enumerate(loop):
        ok = batch.errors[i] is None
        agree &= ok == isinstance(ref, pd.DataFrame)
        if ok and isinstance(ref, pd.DataFrame):
            for q, v in _deviation(batch.trajectory(i), ref).items():
                dev[q] = max(dev[q], v)
    ref_err = {f"ref_err_{who}_{q}": 0.0 for who in ("batched", "lsoda") for q in QUANTITIES}
    for i in range(min(reference, n)):
        if batch.errors[i] is not None or not isinstance(loop[i], pd.DataFrame):
            continue
        p, m, f, a0 = traj[i]
        radau = simulate(p, history, model=m, A0=a0, friction=f, method="Radau", rtol=1e-13, atol=1e-15)
        for who, tab in (("batched", batch.trajectory(i)), ("lsoda", loop[i])):
            for q, v in _deviation(tab, radau).items():
                ref_err[f"ref_err_{who}_{q}"] = max(ref_err[f"ref_err_{who}_{q}"], v)
    st = batch.status
    return {
        "N": n, "n_model1": M.count("model1"), "n_model2": M.count("model2"),
        "rows_per_trajectory": len(batch.table) // max(1, int(batch.ok.sum())) if batch.ok.any() else 0,
        "batched_s": t_batch, "loop_s": t_loop, "speedup": t_loop / t_batch,
        "max_dev_A_norm": dev["A_norm"], "max_dev_theta_A_deg": dev["theta_A"], "max_dev_mu": dev["mu"],
        "n_fallback": int((st.solver != "batched").sum()), "n_failed": int((st.status != "ok").sum()),
        "status_agrees": bool(agree), "n_reference": min(reference, n), **ref_err,
    }


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m model.batched_benchmark", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="results/accuracy", help="output folder (default: %(default)s)")
    ap.add_argument("--sizes", type=int, nargs="+", default=list(SIZES), help="batch sizes (default: %(default)s)")
    ap.add_argument("--reference", type=int, default=10,
                    help="trajectories also compared with Radau at rtol 1e-13 (default: %(default)s)")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    if any(n < 1 for n in args.sizes) or args.reference < 0:
        ap.error("--sizes must be >= 1 and --reference >= 0")
    history = steady_shear(STRAIN_AFTER, -1.0)
    simulate_batch(calibrated_params(), history, A0=(0.0, -0.05))     # warm up imports and caches
    rows = []
    for n in args.sizes:
        rows.append(measure(n, history, args.reference, args.seed))
        r = rows[-1]
        print(f"N = {n:5d}: batched {r['batched_s']:.3f} s, loop of simulate {r['loop_s']:.3f} s, "
              f"speedup {r['speedup']:.1f}x, max deviation |A| {r['max_dev_A_norm']:.1e}, "
              f"theta_A {r['max_dev_theta_A_deg']:.1e} deg, mu {r['max_dev_mu']:.1e}, "
              f"fallbacks {r['n_fallback']}, failed {r['n_failed']}", flush=True)
    df = pd.DataFrame(rows)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    df.to_csv(out / "batched_cost.csv", index=False)
    with pd.option_context("display.width", 250, "display.max_columns", 50):
        print(df.to_string(index=False, float_format=lambda v: f"{v:.3g}"))
    print(f"wrote {out / 'batched_cost.csv'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
