"""Command line: ``python -m model simulate`` (and ``python -m model defaults``).

Runs with no arguments on the documented defaults (``model.params.DEFAULT_PARAMS_YAML``
and a Heaviside reversal after 2 units of strain, 3 after) and prints what it used.
Writes ``<out>/<stem>.csv`` (columns of ``model.simulate``, plus ``model``) and
``<out>/<stem>.png`` (|A|, theta_A and mu against strain).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from . import histories
from .integrate import DEFAULT_ATOL, DEFAULT_METHOD, DEFAULT_RTOL, FRICTIONS, METHODS, simulate
from .params import DEFAULT_PARAMS_YAML, default_params, load_params
from .rhs import MODELS


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="python -m model", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="command", required=True)
    sub.add_parser("defaults", help="print the default parameter file (YAML) and exit")
    s = sub.add_parser("simulate", help="integrate the model along a shear history",
                       formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    s.add_argument("--params", help="parameter file written by calibrate (YAML, see model/params.py); "
                   "default: the documented defaults")
    s.add_argument("--model", default="both", choices=list(MODELS) + ["both"])
    s.add_argument("--protocol", default="heaviside", choices=["heaviside", "sinusoidal", "table"])
    s.add_argument("--strain-before", type=float, default=2.0, help="strain before the reversal")
    s.add_argument("--strain-after", type=float, default=3.0, help="strain after the reversal")
    s.add_argument("--transition-strain", type=float, default=0.5,
                   help="sinusoidal: transition length x gammadot (half cosine +U -> -U)")
    s.add_argument("--gammadot", type=float, default=1.0, help="shear rate before the reversal")
    s.add_argument("--table", help="protocol=table: CSV with columns t, gammadot (e.g. a DEM run's)")
    s.add_argument("--method", default=DEFAULT_METHOD, choices=METHODS)
    s.add_argument("--rtol", type=float, default=DEFAULT_RTOL)
    s.add_argument("--atol", type=float, default=DEFAULT_ATOL)
    s.add_argument("--step", type=float, default=None, help="RK4 time step (default: 0.01 strain)")
    s.add_argument("--friction", default="eq2", choices=FRICTIONS)
    s.add_argument("--out", default="results/model", help="output directory")
    s.add_argument("--stem", default=None, help="output file name stem (default: the protocol)")
    return ap


def make_history(args):
    if args.protocol == "heaviside":
        return histories.heaviside(args.strain_before, args.strain_after, args.gammadot)
    if args.protocol == "sinusoidal":
        return histories.sinusoidal(args.strain_before, args.transition_strain, args.strain_after, args.gammadot)
    if not args.table:
        raise ValueError("--protocol table needs --table FILE (CSV with columns t, gammadot)")
    return histories.tabulated(*read_table(args.table))


def read_table(path):
    """Columns ``t`` and ``gammadot`` of a protocol table (CSV), checked.

    Raises
    ------
    ValueError
        One line naming the file and the problem: not found, a directory, not
        a CSV, a missing column, or a non-numeric or non-finite value (with
        its data row, counted from 1).
    """
    path = Path(path)
    if not path.exists():
        raise ValueError(f"{path}: --table file not found")
    if path.is_dir():
        raise ValueError(f"{path}: --table is a directory, expected a CSV with columns t, gammadot")
    try:
        tab = pd.read_csv(path)
    except (OSError, UnicodeDecodeError, pd.errors.ParserError, pd.errors.EmptyDataError) as exc:
        raise ValueError(f"{path}: not a readable CSV ({str(exc).strip().splitlines()[0]})") from None
    tab.columns = [str(c).strip() for c in tab.columns]
    missing = {"t", "gammadot"} - set(tab.columns)
    if missing:
        raise ValueError(f"{path}: missing column(s) {sorted(missing)}; a table needs columns t, gammadot")
    out = []
    for col in ("t", "gammadot"):
        values = pd.to_numeric(tab[col], errors="coerce").to_numpy(dtype=float)
        bad = ~np.isfinite(values)
        if bad.any():
            raise ValueError(f"{path}: column '{col}' is not a finite number at data row {int(np.argmax(bad)) + 1}")
        out.append(values)
    return out


def plot(tables: dict, path: Path, title: str) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 1, figsize=(6.5, 8), sharex=True)
    for name, tab in tables.items():
        s = tab["strain"].to_numpy()
        # plot against accumulated |strain| so the reversal does not fold the curve back
        s_abs = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(s)))])
        axes[0].plot(s_abs, tab["A_norm"], label=name)
        axes[1].plot(s_abs, tab["theta_A"], label=name)
        axes[2].plot(s_abs, tab["mu"], label=name)
    axes[0].set_ylabel("|A| (-)")
    axes[1].set_ylabel(r"$\theta_A$ (deg)")
    axes[1].axhline(90.0, color="0.7", lw=0.8, ls=":")
    axes[2].set_ylabel(r"$\mu = |\sigma_{xy}|/p$ (-)")
    axes[2].set_xlabel(r"accumulated strain $\int|\dot\gamma|\,dt$ (-)")
    for ax in axes:
        ax.legend()
        ax.grid(alpha=0.3)
    axes[0].set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    if args.command == "defaults":
        print(DEFAULT_PARAMS_YAML, end="")
        return 0
    try:
        params = load_params(args.params) if args.params else default_params()
        history = make_history(args)
        models = list(MODELS) if args.model == "both" else [args.model]
        src = args.params or "built-in defaults (model.params.DEFAULT_PARAMS_YAML)"
        print(f"parameters: {src}")
        for block, values in params.to_dict().items():
            if block in ("model1", "model2", "friction_eq2", "friction_quadratic"):
                print(f"  {block}: " + ", ".join(f"{k}={v:g}" for k, v in values.items()))
        proto = {"heaviside": f"strain_before={args.strain_before:g}, strain_after={args.strain_after:g}",
                 "sinusoidal": f"strain_before={args.strain_before:g}, transition_strain="
                               f"{args.transition_strain:g}, strain_after={args.strain_after:g}",
                 "table": f"table={args.table}"}[args.protocol]
        print(f"protocol: {args.protocol} ({proto}, gammadot={args.gammadot:g})")
        tol = f"step={args.step}" if args.method == "RK4" else f"rtol={args.rtol:g}, atol={args.atol:g}"
        print(f"method: {args.method} ({tol}); friction: {args.friction}")
        tables = {m: simulate(params, history, model=m, method=args.method, rtol=args.rtol, atol=args.atol,
                              step=args.step, friction=args.friction) for m in models}
    except ValueError as err:  # bad input: one line, no traceback (PoleError is a ValueError too)
        print(f"python -m model simulate: error: {err}", file=sys.stderr)
        return 2
    out = Path(args.out)
    stem = args.stem or args.protocol
    csv = out / f"{stem}.csv"
    png = out / f"{stem}.png"
    try:
        out.mkdir(parents=True, exist_ok=True)
        pd.concat([t.assign(model=m) for m, t in tables.items()]).to_csv(csv, index=False)
        plot(tables, png, f"{args.protocol} reversal ({args.friction} friction, {args.method})")
    except OSError as err:
        print(f"python -m model simulate: error: --out {out}: cannot write ({err.strerror or err})", file=sys.stderr)
        return 2
    print(f"wrote {csv} and {png}")
    return 0
