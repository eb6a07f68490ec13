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

Times are medians of interleaved repeats (5 for N <= 60, fewer above), wall
and CPU (``*_cpu_s``: this process only, less sensitive to a shared machine).
For the trajectories on which the two integrators differ most (the worst
``ceil(--reference / 3)`` in each of |A|, theta_A and mu, default 4 each), both are also compared with Radau at rtol 1e-13 (columns
``ref_err_*``): that says which of the two a deviation comes from.
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


def _timed(run):
    w, c = time.perf_counter(), time.process_time()
    out = run()
    return out, time.perf_counter() - w, time.process_time() - c


def _loop(traj, history):
    out = []
    for p, m, f, a0 in traj:
        try:
            out.append(simulate(p, history, model=m, A0=a0, friction=f))
        except (ValueError, FloatingPointError, RuntimeError) as exc:
            out.append(exc)
    return out


def measure(n, history, reference=10, seed=0, repeats=None):
    """One row of the table: batched and looped times (median of interleaved repeats), deviations, statuses."""
    traj = trajectories(n, seed)
    P, M, F, A0 = (list(x) for x in zip(*traj))
    repeats = repeats or max(1, min(5, 300 // n))
    times = {"batched": [], "loop": []}
    for _ in range(repeats):     # interleaved, so that both see the same load of a shared machine
        batch, wall, cpu = _timed(lambda: simulate_batch(P, history, model=M, A0=A0, friction=F))
        times["batched"].append((wall, cpu))
        loop, wall, cpu = _timed(lambda: _loop(traj, history))
        times["loop"].append((wall, cpu))
    med = {k: np.median(np.array(v), axis=0) for k, v in times.items()}

    dev = np.zeros((n, len(QUANTITIES)))
    agree = True
    for i, ref in enumerate(loop):
        ok = batch.errors[i] is None
        agree &= ok == isinstance(ref, pd.DataFrame)
        if ok and isinstance(ref, pd.DataFrame):
            dev[i] = list(_deviation(batch.trajectory(i), ref).values())
    # the trajectories where the two disagree most, against Radau: which of the two the deviation comes from
    ref_err = {f"ref_err_{who}_{q}": 0.0 for who in ("batched", "lsoda") for q in QUANTITIES}
    per_quantity = -(-reference // len(QUANTITIES))                 # the worst of each quantity in turn
    worst = np.unique(np.concatenate([np.argsort(-dev[:, c])[:per_quantity] for c in range(len(QUANTITIES))]))
    worst = worst[:0] if reference == 0 else worst
    for i in worst:
        if not dev[i].any():
            continue
        p, m, f, a0 = traj[i]
        radau = simulate(p, history, model=m, A0=a0, friction=f, method="Radau", rtol=1e-13, atol=1e-15)
        for who, tab in (("batched", batch.trajectory(i)), ("lsoda", loop[i])):
            for q, v in _deviation(tab, radau).items():
                ref_err[f"ref_err_{who}_{q}"] = max(ref_err[f"ref_err_{who}_{q}"], v)
    st = batch.status
    return {
        "N": n, "n_model1": M.count("model1"), "n_model2": M.count("model2"), "repeats": repeats,
        "batched_s": med["batched"][0], "loop_s": med["loop"][0], "speedup": med["loop"][0] / med["batched"][0],
        "batched_cpu_s": med["batched"][1], "loop_cpu_s": med["loop"][1],
        "speedup_cpu": med["loop"][1] / med["batched"][1],
        "max_dev_A_norm": dev[:, 0].max(), "max_dev_theta_A_deg": dev[:, 1].max(), "max_dev_mu": dev[:, 2].max(),
        "n_fallback": int((st.solver != "batched").sum()), "n_failed": int((st.status != "ok").sum()),
        "status_agrees": bool(agree), "n_reference": len(worst), **ref_err,
    }


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m model.batched_benchmark", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="results/accuracy", help="output folder (default: %(default)s)")
    ap.add_argument("--sizes", type=int, nargs="+", default=list(SIZES), help="batch sizes (default: %(default)s)")
    ap.add_argument("--reference", type=int, default=10,
                    help="trajectories (those where the two differ most) also compared with Radau at rtol 1e-13 "
                         "(default: %(default)s)")
    ap.add_argument("--repeats", type=int, default=None,
                    help="interleaved repeats per size (default: 5 for N <= 60, 300 // N above, at least 1)")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    if any(n < 1 for n in args.sizes) or args.reference < 0 or (args.repeats is not None and args.repeats < 1):
        ap.error("--sizes and --repeats must be >= 1, --reference >= 0")
    history = steady_shear(STRAIN_AFTER, -1.0)
    simulate_batch(calibrated_params(), history, A0=(0.0, -0.05))     # warm up imports and caches
    rows = []
    for n in args.sizes:
        rows.append(measure(n, history, args.reference, args.seed, args.repeats))
        r = rows[-1]
        print(f"N = {n:5d}: batched {r['batched_s']:.3f} s, loop of simulate {r['loop_s']:.3f} s, "
              f"speedup {r['speedup']:.1f}x (CPU {r['speedup_cpu']:.1f}x), max deviation |A| {r['max_dev_A_norm']:.1e}, "
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
