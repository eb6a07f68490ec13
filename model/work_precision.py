"""What accuracy costs in time: a work-precision study of the integrators.

``python -m model.work_precision --out results/accuracy`` writes
``ode_work_precision.csv`` and ``ode_work_precision.png``. For RK4 at several
steps and each scipy method at several tolerances it runs a Heaviside and a
sinusoidal reversal (default Model 1 parameters, 3 units of strain each, from
the steady state), takes the median wall time of repeated runs of
``model.simulate`` and the largest error in |A|, theta_A and mu on 601 report
times against a reference (Radau, rtol 1e-13). The ``pareto`` column marks the
runs no other run beats in both time and error. Takes about a minute.
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import pandas as pd

from .histories import heaviside, sinusoidal
from .integrate import simulate, steady_state
from .params import default_params

CASES = {
    "heaviside": lambda: heaviside(1.0, 2.0),             # 3 units of strain, reversal at 1
    "sinusoidal": lambda: sinusoidal(1.0, 0.5, 1.5),      # 1 + (0.5 transition) + 1.5
}
RK4_STRAIN_STEPS = (0.1, 0.05, 0.02, 0.01, 0.005, 0.002)
TOLERANCES = (1e-4, 1e-6, 1e-8, 1e-10)
SCIPY_METHODS = ("RK23", "RK45", "DOP853", "Radau", "BDF", "LSODA")


def _errors(tab, ref):
    return {
        "err_A_norm": float(np.max(np.abs(tab.A_norm.to_numpy() - ref.A_norm.to_numpy()))),
        "err_theta_A_deg": float(np.max(np.abs(tab.theta_A.to_numpy() - ref.theta_A.to_numpy()))),
        "err_mu": float(np.max(np.abs(tab.mu.to_numpy() - ref.mu.to_numpy()))),
    }


def _median_time(run, repeats, budget=2.0):
    times = []
    start = time.perf_counter()
    for _ in range(repeats):
        t0 = time.perf_counter()
        tab = run()
        times.append(time.perf_counter() - t0)
        if time.perf_counter() - start > budget and len(times) >= 3:
            break
    return float(np.median(times)), tab


def pareto_mask(cost, err):
    """True for points that no other point beats in both cost and error."""
    cost, err = np.asarray(cost), np.asarray(err)
    out = np.ones(len(cost), dtype=bool)
    for i in range(len(cost)):
        dominated = (cost <= cost[i]) & (err <= err[i]) & ((cost < cost[i]) | (err < err[i]))
        out[i] = not np.any(dominated)
    return out


def study(repeats=7, model="model1") -> pd.DataFrame:
    p = default_params()
    A0 = steady_state(p, model)[:2]
    rows = []
    for case, make in CASES.items():
        h = make()
        t_eval = np.linspace(0.0, h.t_end, 601)
        ref = simulate(p, h, model=model, A0=A0, method="Radau", rtol=1e-13, atol=1e-15, t_eval=t_eval)
        configs = [("RK4", dict(step=s), s, np.nan) for s in RK4_STRAIN_STEPS]
        configs += [(m, dict(rtol=r, atol=r * 1e-2), np.nan, r) for m in SCIPY_METHODS for r in TOLERANCES]
        for method, kw, step, rtol in configs:
            run = lambda: simulate(p, h, model=model, A0=A0, method=method, t_eval=t_eval, **kw)  # noqa: E731
            wall, tab = _median_time(run, repeats)
            err = _errors(tab, ref)
            rows.append({"case": case, "method": method, "step": step, "rtol": rtol,
                         "atol": rtol * 1e-2 if np.isfinite(rtol) else np.nan, "wall_time_s": wall, **err,
                         "err_max_abs": max(err["err_A_norm"], err["err_mu"]),
                         "err_max_all": max(err.values())})
    df = pd.DataFrame(rows)
    df["pareto"] = False
    for case, g in df.groupby("case"):
        df.loc[g.index, "pareto"] = pareto_mask(g.wall_time_s, g.err_max_all)
    return df


def plot(df, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = list(df.case.unique())
    fig, axes = plt.subplots(1, len(cases), figsize=(5.5 * len(cases), 4.5), sharey=True)
    for ax, case in zip(np.atleast_1d(axes), cases):
        g = df[df.case == case]
        for method, gm in g.groupby("method", sort=False):
            gm = gm.sort_values("wall_time_s")
            ax.loglog(gm.wall_time_s * 1e3, gm.err_max_all, "o-", label=method)
        front = g[g.pareto].sort_values("wall_time_s")
        ax.loglog(front.wall_time_s * 1e3, front.err_max_all, "k--", lw=0.8, label="Pareto front")
        ax.axhline(1e-6, color="0.6", lw=0.8, ls=":")
        ax.set_xlabel("wall time, median (ms)")
        ax.set_title(f"{case} reversal, Model 1, 3 units of strain")
        ax.grid(alpha=0.3, which="both")
    np.atleast_1d(axes)[0].set_ylabel("largest error in |A|, theta_A (deg), mu")
    np.atleast_1d(axes)[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m model.work_precision", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="results/accuracy")
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    df = study(repeats=args.repeats)
    df.to_csv(out / "ode_work_precision.csv", index=False)
    plot(df, out / "ode_work_precision.png")
    cols = ["case", "method", "step", "rtol", "wall_time_s", "err_A_norm", "err_theta_A_deg", "err_mu", "pareto"]
    with pd.option_context("display.width", 200, "display.max_rows", 200):
        print(df[cols].to_string(index=False, float_format=lambda v: f"{v:.3g}"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
