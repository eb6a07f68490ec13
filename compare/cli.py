r"""Command line of the model-against-DEM comparison.

::

    python -m compare predict --dem results/dem/p1_I0.001_s1 ... --params results/calibration/all/params.yaml \
        --set all --protocols heaviside sinusoidal [--train-cases LABEL ...] [--train-protocols ...] \
        --out results/compare/all
        # -> predictions.csv, errors.csv, claims.csv, fig4_heaviside.png, fig5_sinusoidal.png
        # (each figure: every reversal of its kind, Heaviside step or half cosine, of every protocol)
    python -m compare heldout --errors results/compare/*/errors.csv --out results/compare/heldout_errors.csv
    python -m compare sensitivity --dem ... --params results/calibration/all/params.yaml --set all \
        --protocols heaviside sinusoidal --out results/compare/all
        # -> sensitivity.csv, sensitivity_band.png
    python -m compare synthetic --out /tmp/dem [--noise]    # DEM-like cases made by model/, for trials

Errors in the inputs exit with status 2 and a message naming the file and the
problem; Model 1's PoleError never stops a run (it is a row in the tables).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from .dem import PROTOCOL_NAME, REVERSAL_PROTOCOLS, DEMInputError

#: Reversal kind (``dem_contract.derived.REVERSAL_KINDS``) -> its figure.
FIGURE_NAMES = {"heaviside": "fig4_heaviside.png", "sinusoidal": "fig5_sinusoidal.png"}


def protocol_name(text: str) -> str:
    """A reversal protocol's name: heaviside, sinusoidal or a reversal schedule's (lower case, digits, '_')."""
    if not PROTOCOL_NAME.match(text) or text == "preshear":
        raise argparse.ArgumentTypeError(f"invalid protocol {text!r}: heaviside, sinusoidal or a reversal "
                                         "schedule's name (lower-case letters, digits, '_')")
    return text


def _cmd_predict(args):
    from . import comparison, figures
    t0 = time.perf_counter()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    friction = {"model2": args.model2_friction}
    c = comparison.run(args.dem, args.params, args.protocols, set_name=args.set, train_cases=args.train_cases,
                       train_protocols=args.train_protocols, friction=friction, dem_smooth=args.dem_smooth)
    c.predictions.to_csv(out / "predictions.csv", index=False)
    c.errors.to_csv(out / "errors.csv", index=False)
    c.claims.to_csv(out / "claims.csv", index=False)
    kinds = args.figures if args.figures is not None else [
        k for k in FIGURE_NAMES if any(e.attrs.get("kind") == k for e in c.ensembles.values())]
    for kind in kinds:   # every reversal of that kind, of every protocol
        figures.reversal_figure(c.ensembles, kind, out / FIGURE_NAMES[kind], zoom=args.zoom,
                                title=f"{kind} reversal: DEM against Model 1 and Model 2 "
                                      f"(calibration set '{args.set}')")
    bad = c.errors[c.errors["status"] != "ok"]
    for _, r in bad.iterrows():
        print(f"warning: {r['model']} on {r['case']} ({r['protocol']}): {r['status']}", file=sys.stderr)
    print(f"compare predict: set {args.set}, {len(args.dem)} case(s) x {len(args.protocols)} protocol(s) "
          f"-> {out} in {time.perf_counter() - t0:.1f} s")
    return 0


def _cmd_heldout(args):
    from . import heldout
    table = heldout.heldout_table(args.errors)
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    table.to_csv(args.out, index=False)
    print(f"compare heldout: {len(args.errors)} set(s) -> {args.out}")
    return 0


def _cmd_sensitivity(args):
    from . import sensitivity
    t0 = time.perf_counter()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    table, n = sensitivity.run(args.dem, args.params, args.protocols, out / "sensitivity_band.png",
                               set_name=args.set, fractions=args.fractions,
                               friction={"model2": args.model2_friction})
    table.to_csv(out / "sensitivity.csv", index=False)
    print(f"compare sensitivity: {n} integrations -> {out} in {time.perf_counter() - t0:.1f} s")
    return 0


def _cmd_synthetic(args):
    from model import default_params, load_params
    from dem_contract.synthetic import FABRIC_NOISE, MU_NOISE, write_ensemble
    params = load_params(args.params) if args.params else default_params()
    noise = dict(fabric_noise=FABRIC_NOISE, mu_noise=MU_NOISE) if args.noise else {}
    paths = write_ensemble(args.out, params, seeds=args.seeds, group=args.group, model=args.model,
                           friction="eq2" if args.model == "model1" else "quadratic", **noise)
    print("\n".join(str(p) for p in paths))
    return 0


def build_parser():
    ap = argparse.ArgumentParser(prog="python -m compare", description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="command", required=True)

    def common(p):
        p.add_argument("--dem", nargs="+", required=True, help="DEM case directories results/dem/<label>")
        p.add_argument("--params", required=True, help="params.yaml of the calibration set")
        p.add_argument("--set", default="all", help="calibration set name (a column of the tables)")
        p.add_argument("--protocols", nargs="+", default=list(REVERSAL_PROTOCOLS), type=protocol_name,
                       help="heaviside, sinusoidal or a reversal schedule's name (one row group per reversal)")
        p.add_argument("--model2-friction", default="quadratic", choices=("quadratic", "eq2"),
                       help="friction law of Model 2 (default: its own, the quadratic law of [15])")
        p.add_argument("--out", required=True, help="output directory")

    p = sub.add_parser("predict", help="Model 1 and 2 on every case: predictions, errors, claims, Fig. 4/5")
    common(p)
    p.add_argument("--train-cases", nargs="*", default=None, help="labels the set was calibrated on (default all)")
    p.add_argument("--train-protocols", nargs="*", default=None, help="protocols it was calibrated on (default all)")
    p.add_argument("--zoom", type=float, default=0.1, help="strain range of the zoom inset (default 0.1)")
    p.add_argument("--figures", nargs="*", default=None, choices=list(FIGURE_NAMES),
                   help="reversal kinds to draw, each with every reversal of that kind "
                        "(default: every kind the runs hold)")
    p.add_argument("--dem-smooth", type=int, default=5, help="running mean (samples) on the DEM for the claims")
    p.set_defaults(func=_cmd_predict)

    p = sub.add_parser("heldout", help="in-sample against out-of-sample errors over calibration sets")
    p.add_argument("--errors", nargs="+", required=True, help="errors.csv of each set")
    p.add_argument("--out", required=True, help="CSV to write")
    p.set_defaults(func=_cmd_heldout)

    p = sub.add_parser("sensitivity", help="predictions under perturbed parameters: table and band figure")
    common(p)
    p.add_argument("--fractions", nargs="+", type=float, default=[0.01, 0.05], help="relative perturbations")
    p.set_defaults(func=_cmd_sensitivity)

    p = sub.add_parser("synthetic", help="write DEM-like cases made by model/ (for trials and tests)")
    p.add_argument("--out", required=True)
    p.add_argument("--params", default=None, help="parameter file (default: model's documented defaults)")
    p.add_argument("--model", default="model1", choices=("model1", "model2"))
    p.add_argument("--seeds", nargs="+", type=int, default=[1, 2, 3, 4])
    p.add_argument("--group", default="p1_I0.001")
    p.add_argument("--noise", action="store_true", help="add the noise of one 500-disk DEM run (docs/data-contract.md)")
    p.set_defaults(func=_cmd_synthetic)
    return ap


def main(argv=None):
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except (DEMInputError, ValueError) as exc:
        print(f"compare {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # a missing input, or an --out that cannot be written
        print(f"compare {args.command}: error: {exc.filename or args.out}: {exc.strerror or exc}", file=sys.stderr)
        return 2
