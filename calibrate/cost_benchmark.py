"""What the batched integrator saves in calibration: every calibration set, ``--integrator loop`` against ``batched``.

``python -m calibrate.cost_benchmark --results results --out results/accuracy`` calibrates
each calibration set of the campaign under ``<results>/dem/`` twice in one run, with
the curve fit and the bootstrap integrating the model one run at a time (``loop``:
``model.simulate``) and in batches (``batched``: ``model.batched.simulate_batch``),
and writes

- ``calibration_cost.csv``: one row per set: wall and CPU time of each path (this
  process only, ``time.process_time``), their ratio, whether the batched path meets
  the target of ``--target`` seconds, and how its parameter table differs from the
  loop's: ``n_outside_interval`` counts the fitted values (every route) of the batched
  table outside the loop table's bootstrap interval, ``max_shift_over_width`` is the
  largest |difference| over the interval's width;
- the profiles' cost (``calibrate.profiles``), batched: ``xc_profile_cpu_s`` is the
  profile of Model 1's X_c alone (``profile_points`` re-fits, after the curve fit;
  target ``--profile-target`` seconds), ``with_profiles_cpu_s`` a whole calibration
  with every profile (X_c and the c_i of both models) and the sensitivity
  matrix, ``profiles_share`` the part of it they take (the loop and batched
  columns above time the calibration without profiles, as before they existed);
- ``calibration_cost_params.csv``: the two values of every parameter of every set,
  the loop's interval and the shift.

Sets: ``all`` (every case and protocol), one per inertial number and one per
pressure when the campaign has several (as the workflow makes them), and any
``--protocol-set NAME=PROTOCOL[,PROTOCOL]`` (every case, those protocols). Case
directories are those of ``<results>/dem/`` with a ``preshear.csv``.

Without DEM cases there (``--synthetic``, or an empty ``<results>/dem/``), a
model-made campaign of the quick preset's shape is written and timed instead
(``dem_contract.synthetic`` through ``calibrate.synthetic``: 2 inertial numbers x
3 seeds, Heaviside and sinusoidal reversals of 0.6 strain after a pre-shear of
1.5, DEM-magnitude noise, the round-trip test's Model 1 parameters); the
``data`` column says which.

Exit status 2 with a one-line message for bad options.
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd

from dem_contract.labels import parse_case_label

from . import curves_integration, io, pipeline, profiles, tables
from .problem import pose
from .settings import Settings

SYNTHETIC_M1 = dict(a1=-0.85, b1=0.0, c1=-3000.0, a2=-5.0, b2=100.0, c2=2000.0, X_c=0.0827)
QUICK_SHAPE = dict(inertial_numbers=(2e-3, 5e-3), seeds=(1, 2, 3), preshear_strain=1.5, reversal_strain=0.6,
                   transition_strain=0.1, coarse=0.005)


def write_synthetic_quick(root) -> list:
    """A model-made campaign of the quick preset's shape under ``root`` (module Notes); its case directories."""
    from model import default_params, params_from_dict

    from . import synthetic

    d = default_params().to_dict()
    d["model1"] = dict(SYNTHETIC_M1)
    truth = params_from_dict(d)
    q = QUICK_SHAPE
    dirs = []
    for I in q["inertial_numbers"]:
        dirs += synthetic.write_ensemble(root, truth, seeds=q["seeds"], group=f"p100000_I{I:g}", I=I,
                                         preshear_strain=q["preshear_strain"], reversal_strain=q["reversal_strain"],
                                         transition_strain=q["transition_strain"], coarse=q["coarse"])
    return dirs


def calibration_sets(case_dirs, protocol_sets: dict) -> dict:
    """Set name -> (case directories, protocols): ``all``, one per I and per p when several, ``protocol_sets``."""
    parts = {d: parse_case_label(Path(d).name) or {} for d in case_dirs}
    sets = {"all": (list(case_dirs), io.REVERSAL_PROTOCOLS)}
    for key, prefix in (("inertial_number", "I"), ("pressure", "p")):
        values = sorted({p[key] for p in parts.values() if key in p})
        if len(values) > 1:
            for v in values:
                sets[f"{prefix}{v:g}"] = ([d for d, p in parts.items() if p.get(key) == v], io.REVERSAL_PROTOCOLS)
    for name, protocols in protocol_sets.items():
        sets[name] = (list(case_dirs), tuple(protocols))
    return sets


def _timed(dirs, out, settings):
    w0, c0 = time.perf_counter(), time.process_time()
    pipeline.run(dirs, out, settings, log=lambda m: None)
    return time.perf_counter() - w0, time.process_time() - c0


def compare_tables(loop: pd.DataFrame, batched: pd.DataFrame) -> pd.DataFrame:
    """The two ``params_table.csv`` side by side, with the shift over the loop's interval width."""
    keys = ["route", "block", "parameter"]
    m = loop[keys + ["value", "low", "high"]].merge(batched[keys + ["value"]], on=keys, suffixes=("_loop", "_batched"))
    m["shift"] = m["value_batched"] - m["value_loop"]
    width = (m["high"] - m["low"]).to_numpy()
    with np.errstate(divide="ignore", invalid="ignore"):
        m["shift_over_width"] = np.where(width > 0, np.abs(m["shift"]) / width, np.where(m["shift"] == 0, 0.0, np.inf))
    m["inside_interval"] = (m["value_batched"] >= m["low"]) & (m["value_batched"] <= m["high"])
    return m


def profile_cost(dirs, settings: Settings, work: Path) -> tuple:
    """CPU seconds of the X_c profile alone (``settings.profile.n_points`` re-fits, batched) and of a calibration
    with every profile (``pipeline.run``, batched), in this process."""
    s = replace(settings, curves_options=replace(settings.curves_options, integrator="batched"))
    problem = pose(dirs, s)
    backsolve = pipeline.fit_backsolve(problem, pipeline.fit_friction(problem))
    curves = pipeline.fit_curves(problem, backsolve, lambda m: None)
    c0 = time.process_time()
    profiles.profile(problem, backsolve.doc, "model1", curves.fits["model1"].values, names=("X_c",))
    xc = time.process_time() - c0
    return xc, _timed(dirs, work, s)[1]


def run(case_dirs, data: str, out: Path, protocol_sets: dict, settings: Settings, target: float,
        work: Path, log=print, profile_target: float = 60.0):
    rows, params = [], []
    for name, (dirs, protocols) in calibration_sets(case_dirs, protocol_sets).items():
        with_profiles = replace(settings, protocols=tuple(protocols), figures=False)
        s = replace(with_profiles, profile=replace(settings.profile, n_points=0))   # the integrators compared alone
        times, tabs = {}, {}
        for integrator in curves_integration.INTEGRATORS[::-1]:   # loop first, then batched
            o = work / name / integrator
            one = replace(s, curves_options=replace(s.curves_options, integrator=integrator))
            times[integrator] = _timed(dirs, o, one)
            tabs[integrator] = pd.read_csv(o / "params_table.csv")
            log(f"{name} {integrator}: {times[integrator][0]:.1f} s wall, {times[integrator][1]:.1f} s CPU")
        cmp = compare_tables(tabs["loop"], tabs["batched"])
        (lw, lc), (bw, bc) = times["loop"], times["batched"]
        xc, pc = profile_cost(dirs, with_profiles, work / name / "profiles")
        log(f"{name}: X_c profile {xc:.1f} s CPU; calibration with profiles {pc:.1f} s CPU")
        rows.append({"set": name, "data": data, "n_cases": len(dirs), "protocols": "+".join(protocols),
                     "n_boot": s.n_boot, "loop_wall_s": lw, "loop_cpu_s": lc, "batched_wall_s": bw,
                     "batched_cpu_s": bc, "speedup_wall": lw / bw, "speedup_cpu": lc / bc, "target_s": target,
                     "batched_meets_target": bool(bc <= target), "n_parameters": len(cmp),
                     "n_outside_interval": int((~cmp["inside_interval"]).sum()),
                     "max_shift_over_width": float(cmp["shift_over_width"].max()),
                     "profile_points": with_profiles.profile.n_points, "xc_profile_cpu_s": xc,
                     "xc_profile_target_s": profile_target, "xc_profile_meets_target": bool(xc <= profile_target),
                     "with_profiles_cpu_s": pc, "profiles_share": 1.0 - bc / pc if pc > 0 else float("nan")})
        params.append(cmp.assign(set=name))
    cost = pd.DataFrame(rows)
    tables.write_csv(cost, out / "calibration_cost.csv")
    tables.write_csv(pd.concat(params, ignore_index=True), out / "calibration_cost_params.csv")
    return cost


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python -m calibrate.cost_benchmark", description=__doc__.splitlines()[0])
    p.add_argument("--results", default="results", help="results directory whose dem/ holds the campaign's cases")
    p.add_argument("--out", default="results/accuracy", help="where calibration_cost.csv is written")
    p.add_argument("--synthetic", action="store_true",
                   help="time a model-made campaign of the quick preset's shape even if DEM cases exist")
    p.add_argument("--protocol-set", action="append", default=[], metavar="NAME=PROTOCOL[,PROTOCOL]",
                   help="an extra set of every case with these protocols (e.g. heaviside_only=heaviside)")
    p.add_argument("--bootstrap", type=int, default=Settings.n_boot, help="bootstrap replicates per set")
    p.add_argument("--target", type=float, default=10.0, help="target CPU seconds per set (batched)")
    p.add_argument("--profile-target", type=float, default=60.0,
                   help="target CPU seconds of the X_c profile per set (batched)")
    p.add_argument("--work", help="keep each calibration's outputs here (default: a temporary directory)")
    return p


def main(argv=None) -> int:
    a = parser().parse_args(argv)
    protocol_sets = {}
    for spec in a.protocol_set:
        name, _, protos = spec.partition("=")
        protos = tuple(x for x in protos.split(",") if x)
        if not name or not protos or not set(protos) <= set(io.REVERSAL_PROTOCOLS):
            print(f"cost_benchmark: --protocol-set {spec!r}: expected NAME=PROTOCOL[,PROTOCOL] with protocols "
                  f"from {io.REVERSAL_PROTOCOLS}", file=sys.stderr)
            return 2
        protocol_sets[name] = protos
    if a.bootstrap < 1 or a.target <= 0 or a.profile_target <= 0:
        print("cost_benchmark: --bootstrap must be >= 1, --target and --profile-target > 0", file=sys.stderr)
        return 2
    dem = Path(a.results) / "dem"
    case_dirs = sorted(str(d) for d in dem.glob("*") if (d / "preshear.csv").is_file()) if dem.is_dir() else []
    log = lambda m: print(m, file=sys.stderr, flush=True)  # noqa: E731
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(a.work) if a.work else Path(tmp)
        if a.synthetic or not case_dirs:
            case_dirs = [str(d) for d in write_synthetic_quick(work / "synthetic_dem")]
            data = "model-made quick-shaped campaign (dem_contract.synthetic; no DEM cases used)"
        else:
            data = f"DEM cases of {dem}"
        log(f"cost_benchmark: {len(case_dirs)} case(s), {data}")
        try:
            cost = run(case_dirs, data, Path(a.out), protocol_sets, Settings(n_boot=a.bootstrap),
                       a.target, work, log, a.profile_target)
        except io.DEMInputError as exc:
            print(f"cost_benchmark: bad DEM input: {exc}", file=sys.stderr)
            return 2
    with pd.option_context("display.width", 200, "display.max_columns", 30):
        print(cost.drop(columns=["data"]).to_string(index=False, float_format=lambda x: f"{x:.3g}"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
