"""Command line: ``python -m calibrate --dem <case_dir> [...] --out results/calibration [options]``.

Exit status 2 with a one-line message naming the file and the problem for bad
DEM input (``DEMInputError``) or bad options; the ``--out`` folders this call
created are removed then (a refused calibration leaves no empty or half-written folder).
"""
from __future__ import annotations

import argparse
import re
import sys

from dem_contract.folders import new_folders, remove_new

from . import backsolve, curves_integration, freeform, io, profiles, smoothing
from .pipeline import run
from .settings import Settings

PROTOCOL_NAME = re.compile(r"^[a-z][a-z0-9_]*$")


def protocol_name(text: str) -> str:
    """A reversal protocol's name: heaviside, sinusoidal or a reversal schedule's (lower case, digits, '_')."""
    if not PROTOCOL_NAME.match(text) or text == "preshear":
        raise argparse.ArgumentTypeError(f"invalid protocol {text!r}: heaviside, sinusoidal or a reversal "
                                         "schedule's name (lower-case letters, digits, '_')")
    return text


def parser() -> argparse.ArgumentParser:
    sd, bd, rd = smoothing.SmoothingSettings(), backsolve.BacksolveSettings(), curves_integration.CurvesOptions()
    p = argparse.ArgumentParser(prog="python -m calibrate", description=__doc__.splitlines()[0])
    p.add_argument("--dem", nargs="+", required=True, metavar="CASE_DIR",
                   help="case directories results/dem/<case>/ (seeds of one pressure and I form the ensemble)")
    p.add_argument("--out", required=True, help="output directory, e.g. results/calibration")
    p.add_argument("--protocols", nargs="+", default=list(Settings.protocols), type=protocol_name,
                   help="reversal runs to learn from: heaviside, sinusoidal or a reversal schedule's name")
    g = p.add_argument_group("smoothing (Savitzky-Golay in path strain)")
    g.add_argument("--sg-fine-window", type=float, default=sd.fine_window, help="window (strain) after a reversal")
    g.add_argument("--sg-coarse-window", type=float, default=sd.coarse_window, help="window (strain) elsewhere")
    g.add_argument("--sg-fine-span", type=float, default=sd.fine_span, help="strain after a reversal using the fine window")
    g.add_argument("--sg-order", type=int, default=sd.order)
    g = p.add_argument_group("back-solve")
    g.add_argument("--rate-min", type=float, default=bd.rate_min, help="drop samples with |gammadot| below this fraction of the run's median")
    g.add_argument("--skip", type=float, default=bd.skip, help="drop samples closer than this strain after a reversal")
    g.add_argument("--bin-width", type=float, default=bd.bin_width)
    g.add_argument("--min-bin-samples", type=int, default=bd.min_samples)
    g.add_argument("--cond-max", type=float, default=bd.cond_max)
    g = p.add_argument_group("curve fit (route 2) and bootstrap")
    g.add_argument("--route2-evals", type=int, default=rd.max_evals, help="model evaluations per curve fit (route 2)")
    g.add_argument("--route2-rtol", type=float, default=rd.rtol)
    g.add_argument("--route2-method", default=rd.method)
    g.add_argument("--integrator", choices=curves_integration.INTEGRATORS, default=rd.integrator,
                   help="curve fit and bootstrap: 'batched' integrates all runs and Jacobian points of a step in one "
                        "model.batched.simulate_batch call; 'loop' calls model.simulate per run")
    g.add_argument("--mu-weight", type=float, default=rd.mu_weight)
    g.add_argument("--bootstrap", type=int, default=Settings.n_boot, help="bootstrap replicates over seeds")
    g.add_argument("--bootstrap-evals", type=int, default=Settings.boot_evals, help="model evaluations per replicate fit")
    g.add_argument("--seed", type=int, default=Settings.seed, help="bootstrap random seed")
    g = p.add_argument_group("identifiability (profiles of the curve fit's objective)")
    g.add_argument("--profile-points", type=int, default=profiles.ProfileSettings.n_points,
                   help="grid points per profiled parameter (X_c and the c_i); 0: no profiles")
    g.add_argument("--profile-evals", type=int, default=profiles.ProfileSettings.evals,
                   help="model evaluations per profile point's re-fit")
    g = p.add_argument_group("other")
    g.add_argument("--steady-weight", type=float, default=Settings.steady_weight)
    g.add_argument("--min-samples", type=int, default=Settings.min_samples, help="fewest rows accepted per DEM file")
    g.add_argument("--no-figures", action="store_true")
    g = p.add_argument_group("free-form alphas (upper bound of any X-dependent Eq. 4; calibrate/freeform.py)")
    g.add_argument("--freeform", action="store_true",
                   help="fit alpha1(X), alpha2(X) as penalised splines (penalty by leave-one-seed-out CV), "
                        "score them against Models 1 and 2 on held-out seeds: freeform.csv, and on Figs. 3a, 3b")
    g.add_argument("--freeform-breaks", type=int, default=freeform.FreeformSettings.n_breaks,
                   help="spline breaks over the X range visited (at least 2)")
    g.add_argument("--freeform-layouts", nargs="+", type=knot_layout, default=None, metavar="BREAKS:CROWDING",
                   help="knot layouts the cross-validation chooses among (default: --freeform-breaks evenly "
                        "spaced, crowded, and 2 more crowded; crowding 1 is even)")
    g.add_argument("--freeform-penalties", nargs="+", type=penalty, default=list(freeform.FreeformSettings.penalties),
                   help="roughness penalties the cross-validation chooses among")
    return p


def knot_layout(text: str) -> tuple:
    """``BREAKS:CROWDING`` (for instance ``5:2``) -> (5, 2.0), a layout of ``freeform.breaks_for``, checked
    by ``freeform.FreeformSettings`` (so the pre-flight refuses a bad one before any DEM)."""
    try:
        n, crowd = text.split(":")
        layout = (int(n), float(crowd))
        freeform.FreeformSettings(layouts=(layout,))
    except ValueError as exc:
        raise argparse.ArgumentTypeError(f"{text!r}: expected BREAKS:CROWDING with BREAKS an integer >= 2 and "
                                         f"CROWDING >= 1, for instance 5:2 ({exc})") from None
    return layout


def penalty(text: str) -> float:
    """A roughness penalty of the free-form cross-validation: a positive number."""
    try:
        value = float(text)
        freeform.FreeformSettings(penalties=(value,))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: expected a positive number") from None
    return value


def freeform_settings(a) -> freeform.FreeformSettings | None:
    """The free-form fit's settings from parsed arguments; None without ``--freeform``."""
    if not a.freeform:
        return None
    return freeform.FreeformSettings(n_breaks=a.freeform_breaks, layouts=a.freeform_layouts,
                                     penalties=tuple(a.freeform_penalties))


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    a = parser().parse_args(argv)
    if a.profile_points < 0 or a.profile_points == 1 or a.profile_evals < 1:
        print(f"calibrate: --profile-points {a.profile_points} / --profile-evals {a.profile_evals}: expected "
              f"0 (no profiles) or >= 2 points and >= 1 evaluation", file=sys.stderr)
        return 2
    created, done = [], False
    try:
        created = new_folders(a.out)  # before any work: a bad --out fails at once
        settings = Settings(
            protocols=tuple(a.protocols),
            smoothing=smoothing.SmoothingSettings(fine_window=a.sg_fine_window, coarse_window=a.sg_coarse_window,
                                                  fine_span=a.sg_fine_span, order=a.sg_order),
            backsolve=backsolve.BacksolveSettings(rate_min=a.rate_min, skip=a.skip, bin_width=a.bin_width,
                                                  min_samples=a.min_bin_samples, cond_max=a.cond_max),
            curves_options=curves_integration.CurvesOptions(max_evals=a.route2_evals, rtol=a.route2_rtol,
                                                            method=a.route2_method, integrator=a.integrator,
                                                            mu_weight=a.mu_weight),
            steady_weight=a.steady_weight, n_boot=a.bootstrap, boot_evals=a.bootstrap_evals, seed=a.seed,
            min_samples=a.min_samples, figures=not a.no_figures,
            freeform=freeform_settings(a),
            profile=profiles.ProfileSettings(n_points=a.profile_points, evals=a.profile_evals))
        run(a.dem, a.out, settings, log=lambda m: print(m, file=sys.stderr, flush=True),
            argv=["python -m calibrate", *argv])
        done = True
    except io.DEMInputError as exc:
        print(f"calibrate: bad DEM input: {exc}", file=sys.stderr)
        return 2
    except ValueError as exc:
        print(f"calibrate: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # an --out that cannot be written (a file in its path, no permission, disk full)
        print(f"calibrate: cannot write {exc.filename or a.out}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    finally:
        if not done:
            remove_new(created)
    return 0


if __name__ == "__main__":
    sys.exit(main())
