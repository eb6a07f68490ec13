r"""Coverage of the reported 95 % intervals on model-made data with DEM-like noise.

One realisation is a calibration set like one inertial number of the quick
campaign (3 seeds, a pre-shear of 1.5 and Heaviside and sinusoidal reversals
of 0.6 strain, ``cost_benchmark.QUICK_SHAPE``), made by a known truth
(``dem_contract.synthetic`` through ``calibrate.synthetic``) and calibrated
by ``pipeline.run``. Two truths, each the law a calibration block assumes
(a friction law the calibrated model does not use biases its c_i through
the friction residuals, so Model 2's data carry its own quadratic law):

- ``model2``: Model 2 with the quadratic friction law (as fitted on the quick
  campaign, set ``all``); checked: Model 2's c_i (the curve fit) and the quadratic law;
- ``eq2``: Model 1 with Eq. 2 (the round-trip test's truth); checked: Eq. 2.

The data carry the two noises the DEM has:

- per-sample noise of the 500-disk runs (``calibrate.synthetic.DEFAULTS``);
- seed-to-seed variation: each seed's parameters are the truth times
  :math:`1 + \epsilon`, :math:`\epsilon \sim N(0, \text{jitter}^2)`, drawn
  per parameter of the truth's ``jittered`` (``TRUTHS``). The truth is the centre of that population,
  the value a new campaign would estimate.

For every realisation and every checked parameter the table records whether
the reported interval (``params_table.csv``'s ``low``, ``high``) and the
bootstrap percentile interval (``boot_low``, ``boot_high``) contain the truth;
``summary`` gives the coverage with its Clopper-Pearson 95 % interval.

``python -m calibrate.coverage --realisations 20 --out coverage.csv`` runs
20 realisations of each truth (about 20 s of CPU each).
"""
from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from model import default_params, params_from_dict

from . import pipeline, profiles, synthetic
from .settings import Settings
from .cost_benchmark import QUICK_SHAPE

#: The truths (module Notes): the blocks each sets, the model and friction law that make its data.
TRUTHS = {
    "model2": {"model": "model2", "friction": "quadratic",
               "blocks": {"model2": dict(c1=-1.6, c2=-19.6, c3=-14.0),
                          "friction_quadratic": dict(m0=0.0897, m1=-2.41, m2=-2.63)},
               "jittered": {"model2": ("c1", "c2", "c3"), "friction_quadratic": ("m0", "m1")},
               "checked": {("curves", "model2"), ("mu_vs_X", "friction_quadratic")}},
    "eq2": {"model": "model1", "friction": "eq2",
            "blocks": {"model1": dict(a1=-0.85, b1=0.0, c1=-3000.0, a2=-5.0, b2=100.0, c2=2000.0, X_c=0.0827),
                       "friction_eq2": dict(X0=0.028, k1=2.7, k3=20.0, k5=9.0e4)},
            "jittered": {"model1": ("a1",), "friction_eq2": ("X0", "k1")},
            "checked": {("mu_vs_X", "friction_eq2")}},
}


def truth_doc(truth: str = "model2") -> dict:
    """The full parameter document of one truth."""
    d = default_params().to_dict()
    d.pop("provenance", None)
    for block, vals in TRUTHS[truth]["blocks"].items():
        d[block] = dict(vals)
    return d


def write_realisation(root, truth: str, k: int, jitter: float, seeds: int = 3) -> list:
    """The case directories of realisation ``k`` of ``truth``: ``seeds`` seeds, each with its own jittered parameters."""
    t = TRUTHS[truth]
    rng = np.random.default_rng(10_000 + k)
    q = QUICK_SHAPE
    I = q["inertial_numbers"][0]
    dirs = []
    for j in range(seeds):
        d = truth_doc(truth)
        for block, names in t["jittered"].items():
            for n in names:
                d[block][n] *= 1.0 + jitter * rng.standard_normal()
        seed = seeds * k + j + 1
        dirs.append(synthetic.write_case(Path(root) / f"p100000_I{I:g}_s{seed}", params_from_dict(d), seed=seed,
                                         model=t["model"], friction=t["friction"], I=I,
                                         preshear_strain=q["preshear_strain"], reversal_strain=q["reversal_strain"],
                                         transition_strain=q["transition_strain"], coarse=q["coarse"]))
    return dirs


def default_settings(truth: str) -> Settings:
    """The calibration's defaults; profiles only where the truth's checked rows use them (Model 2)."""
    models = ("model2",) if truth == "model2" else ()
    return Settings(figures=False, profile=profiles.ProfileSettings(models=models))


def run(n: int, jitter: float = 0.05, truths=tuple(TRUTHS), settings: Settings | None = None, log=print,
        first: int = 0) -> pd.DataFrame:
    """Calibrate ``n`` realisations of each truth; one row per (truth, realisation, block, parameter) checked."""
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for truth in truths:
            t, doc = TRUTHS[truth], truth_doc(truth)
            for k in range(first, first + n):
                dirs = write_realisation(Path(tmp) / f"{truth}{k}", truth, k, jitter)
                out = Path(tmp) / f"cal_{truth}{k}"
                pipeline.run(dirs, out, settings or default_settings(truth), log=lambda m: None)
                tab = pd.read_csv(out / "params_table.csv")
                for _, r in tab.iterrows():
                    if (r["route"], r["block"]) not in t["checked"]:
                        continue
                    v = doc[r["block"]][r["parameter"]]
                    rows.append({"truth": truth, "realisation": k, "block": r["block"], "parameter": r["parameter"],
                                 "true_value": v, "value": r["value"], "low": r["low"], "high": r["high"],
                                 "boot_low": r["boot_low"], "boot_high": r["boot_high"], "interval": r["interval"],
                                 "covered": bool(r["low"] <= v <= r["high"]),
                                 "boot_covered": bool(r["boot_low"] <= v <= r["boot_high"]), "note": r["note"]})
                log(f"coverage: {truth} realisation {k + 1 - first}/{n} done")
    return pd.DataFrame(rows)


def clopper_pearson(k: int, n: int, level: float = 0.95) -> tuple:
    """Exact binomial interval of a proportion k/n."""
    ci = stats.binomtest(k, n).proportion_ci(confidence_level=level, method="exact")
    return float(ci.low), float(ci.high)


def summary(table: pd.DataFrame) -> pd.DataFrame:
    """Coverage per parameter: reported and percentile-bootstrap, with Clopper-Pearson intervals."""
    rows = []
    for (block, name), g in table.groupby(["block", "parameter"], sort=False):
        n, k, kb = len(g), int(g["covered"].sum()), int(g["boot_covered"].sum())
        lo, hi = clopper_pearson(k, n)
        rows.append({"block": block, "parameter": name, "n": n, "coverage": k / n, "coverage_low": lo,
                     "coverage_high": hi, "boot_coverage": kb / n,
                     "median_width": float((g["high"] - g["low"]).median()),
                     "median_boot_width": float((g["boot_high"] - g["boot_low"]).median())})
    return pd.DataFrame(rows)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m calibrate.coverage", description=__doc__.splitlines()[0])
    p.add_argument("--realisations", type=int, default=20, help="realisations of each truth")
    p.add_argument("--truth", action="append", choices=list(TRUTHS), help="the truths to run (default: all)")
    p.add_argument("--first", type=int, default=0, help="index of the first realisation (its noise seeds)")
    p.add_argument("--jitter", type=float, default=0.05, help="seed-to-seed relative sd of the parameters")
    p.add_argument("--out", required=True, help="CSV of every realisation; the summary goes to <out>_summary.csv")
    a = p.parse_args(argv)
    if a.realisations < 1 or a.jitter < 0:
        print("calibrate.coverage: --realisations must be >= 1 and --jitter >= 0", file=sys.stderr)
        return 2
    tab = run(a.realisations, a.jitter, tuple(a.truth or TRUTHS), log=lambda m: print(m, file=sys.stderr, flush=True),
              first=a.first)
    out = Path(a.out)
    tab.to_csv(out, index=False, float_format="%.6g")
    s = summary(tab)
    s.to_csv(out.with_name(out.stem + "_summary.csv"), index=False, float_format="%.4g")
    print(s.to_string(index=False))
    return 0


if __name__ == "__main__":
    sys.exit(main())
