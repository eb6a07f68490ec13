"""Command line: ``python -m dem_study analyse|estimate|stiffness|engines ...`` (see dem_study/README.md)."""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import yaml

from campaign.schedule import makespan
from dem_contract import DEMInputError
from dem_contract.tables import read_table

from . import analysis, engines, engines_figures, figures, grid, stiffness


def _tolerance(items):
    out = {}
    for item in items or []:
        key, _, value = item.partition("=")
        if key not in analysis.DEFAULT_TOLERANCE or not value:
            raise SystemExit(f"--tolerance {item!r}: expected KEY=VALUE with KEY in "
                             f"{', '.join(analysis.DEFAULT_TOLERANCE)}")
        out[key] = float(value)
    return out


def _input_file(path, what: str) -> Path:
    """``path`` as a Path if it is an existing file; a ``StudyInputError`` naming it otherwise."""
    path = Path(path)
    if not path.exists():
        raise analysis.StudyInputError(f"{path}: {what} not found")
    if path.is_dir():
        raise analysis.StudyInputError(f"{path}: is a directory, expected the {what}")
    return path


def read_yaml(path, what: str):
    """Parse a YAML file; malformed YAML is a ``StudyInputError`` naming the file and line."""
    path = _input_file(path, what)
    try:
        return yaml.safe_load(path.read_text())
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"{path}:{mark.line + 1}:{mark.column + 1}" if mark is not None else str(path)
        raise analysis.StudyInputError(
            f"{where}: malformed YAML in the {what}: {getattr(exc, 'problem', None) or exc}") from None


def analyse(args) -> int:
    points_file = _input_file(args.points, "points table (--points)")
    if not Path(args.dem_dir).is_dir():
        raise analysis.StudyInputError(f"{args.dem_dir}: DEM folder (--dem-dir) not found")
    try:  # a cut or ragged table is refused by line
        points = read_table(points_file, ["point"], "the points table of grid.expand")
    except DEMInputError as exc:
        raise analysis.StudyInputError(str(exc)) from None
    tol = _tolerance(args.tolerance)
    edges = analysis.strain_edges(args.heaviside_strain, args.transient_bin)
    results = {p: analysis.load_point(Path(args.dem_dir) / p, p, args.steady_window, edges)
               for p in points["point"].unique()}
    table = analysis.cost_table(points, results, tol)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    table.to_csv(out / "dem_cost.csv", index=False, float_format="%.6g")
    figures.error_against_cost(table, out / "dem_cost.png", tol)
    figures.transients(table, {p: r.curves for p, r in results.items()}, out / "dem_transients.png")
    mu_table, fit = analysis.mu_of_I_table(points, results, args.campaign_I, args.quasi_static_tolerance)
    mu_table.to_csv(out / "mu_of_I.csv", index=False, float_format="%.6g")
    figures.mu_of_I(mu_table, out / "mu_of_I.png")
    repeats = analysis.repeat_table(points, results)
    repeats.to_csv(out / "dem_repeats.csv", index=False, float_format="%.6g")
    camp = mu_table[mu_table["kind"] == "campaign"]
    cheapest = analysis.cheapest_within_tolerance(table)
    summary = {
        "tolerance": {**analysis.DEFAULT_TOLERANCE, **tol},
        "tolerance_rule": "a setting is within tolerance when every deviation from the finest value "
                          "of its axis is at most max(tolerance, seed spread)",
        "seed_spread": {k.removeprefix("seed_spread_"): float(v) for k, v in table.iloc[0].items()
                        if k.startswith("seed_spread_")},
        "cheapest_within_tolerance": cheapest,
        "recommended_setting": analysis.recommended_setting(points, cheapest),
        "mu_of_I_fit": vars(fit),
        "repeats": repeats.to_dict("records"),
        "quasi_static_tolerance": args.quasi_static_tolerance,
        "campaign_quasi_static": {f"{I:g}": {"rel_excess": float(e), "within": bool(w)}
                                  for I, e, w in zip(camp["inertial_number"], camp["rel_excess"],
                                                     camp["within_quasi_static"])},
    }
    (out / "dem_study.json").write_text(json.dumps(summary, indent=2) + "\n")
    print(table[["axis", "value", "wall_time_per_strain_s", "particle_steps_per_s", "d_mu", "d_A_norm",
                 "d_theta_A_deg", "d_transient_mu", "within_tolerance"]].to_string())
    print(json.dumps(summary, indent=2))
    return 0


def estimate(args) -> int:
    config = read_yaml(args.configfile, "config file (--configfile)")
    if not isinstance(config, dict) or not isinstance(config.get("accuracy"), dict):
        raise analysis.StudyInputError(f"{args.configfile}: missing block 'accuracy' (the DEM study's settings)")
    if args.subset:
        config["accuracy"]["subset"] = args.subset
    try:
        est = grid.estimate(config)
    except KeyError as exc:
        raise analysis.StudyInputError(f"{args.configfile}: missing key {exc}") from None
    print(est[["point", "N", "steps", "est_core_s"]].to_string(float_format=lambda x: f"{x:.4g}"))
    total = est["est_core_s"].sum()
    print(f"{len(est)} DEM cases: {total / 3600:.2f} core-hours; "
          f"about {makespan(est['est_core_s'], args.cores) / 3600:.2f} h on {args.cores} cores")
    return 0


def stiffness_study(args) -> int:
    if args.releases:
        with tempfile.TemporaryDirectory(prefix="stiffness-") as tmp:
            cases = stiffness.restore_releases(args.releases, tmp)
            runs = stiffness.runs_table(cases, args.steady_window, args.early_strain)
    else:
        for d in args.cases:
            if not Path(d).is_dir():
                raise analysis.StudyInputError(f"{d}: case folder (--cases) not found")
        runs = stiffness.runs_table(args.cases, args.steady_window, args.early_strain)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    table = stiffness.stiffness_table(runs)
    readings = stiffness.readings_table(runs)
    runs.to_csv(out / "stiffness_runs.csv", index=False)
    table.to_csv(out / "stiffness.csv", index=False)
    readings.to_csv(out / "fabric_readings.csv", index=False)
    stiffness.figure(table, out / "stiffness.png")
    cols = [c for c in (*stiffness.SETTING, "seeds", "mu", "mu_se", "A_norm", "A_norm_se", "X", "X_se", "theta_A_deg", "phi",
                        "Z", "A_min_early", "mu_early", "overlap_mean_d", "core_hours_per_seed") if c in table]
    print(table[cols].to_string(index=False, float_format=lambda x: f"{x:.4g}"))
    if len(readings):
        print(readings.to_string(index=False, float_format=lambda x: f"{x:.4g}"))
    print(f"wrote {out}/stiffness.csv, stiffness_runs.csv, fabric_readings.csv, stiffness.png")
    return 0


def engines_study(args) -> int:
    """The engines side by side (``dem_study.engines``): the agreement table, the cost and the figure."""
    with tempfile.TemporaryDirectory(prefix="engines-") as tmp:   # a release's cases are restored here
        dirs = {engine: engines.case_dirs(folder, args.stage, pattern, Path(tmp) / engine)
                for engine, folder, pattern in (("yade", args.yade, args.yade_cases),
                                                ("lammps", args.lammps, args.lammps_cases))}
        settings = {engine: engines.one_setting(engine, d) for engine, d in dirs.items()}
        cases = engines.cases_table(dirs)
        length = min(engines.transient_length(d, args.stage) for d in cases["dir"])
        if args.early_strain > length + 1e-9:
            raise analysis.StudyInputError(f"--early-strain {args.early_strain:g} is longer than the shortest "
                                           f"{args.stage} transient ({length:g} strain)")
        edges = analysis.strain_edges(length, args.transient_bin)
        pairs, cells, curves = engines.compare(cases, args.stage, edges, args.early_strain, args.steady_window,
                                               args.match_se)
        table = engines.agreement_table(pairs, curves, args.early_strain, args.match_se)
        cost = engines.cost_table(cases, cells, args.stage)
    info = engines.summary(table, cost, args.stage, settings, args.early_strain, args.steady_window, args.match_se)
    paths = engines.write(args.out, args.name, table, cost, info)
    figure = Path(args.out) / f"{args.name}_transients.png"
    engines_figures.transients(curves, dict(zip(cells["cell"], cells["seeds"])), args.stage, args.early_strain, figure)
    print(paths["agreement_md"].read_text())
    print("wrote " + ", ".join(str(p) for p in [*paths.values(), figure]))
    return 0


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m dem_study", description=__doc__)
    sub = p.add_subparsers(dest="command", required=True)
    a = sub.add_parser("analyse", help="cost table, error-against-cost and mu(I) from the study's DEM runs")
    a.add_argument("--points", required=True, help="the study's points table (grid.expand), CSV")
    a.add_argument("--dem-dir", required=True, help="folder holding one case folder per point")
    a.add_argument("--out", required=True, help="output folder")
    a.add_argument("--steady-window", type=float, default=0.5, help="pre-shear strain averaged for steady values")
    a.add_argument("--heaviside-strain", type=float, required=True, help="strain after the reversal")
    a.add_argument("--transient-bin", type=float, default=0.01, help="strain bin of the transient curves")
    a.add_argument("--tolerance", nargs="*", metavar="KEY=VALUE", help="override a tolerance")
    a.add_argument("--campaign-I", type=float, nargs="+", required=True, help="the campaign's inertial numbers")
    a.add_argument("--quasi-static-tolerance", type=float, default=0.05,
                   help="largest (mu - mu_c)/mu_c accepted as quasi-static")
    a.set_defaults(func=analyse)
    e = sub.add_parser("estimate", help="estimated run time of the study's DEM cases")
    e.add_argument("--configfile", required=True)
    e.add_argument("--subset", choices=["default", "full"])
    e.add_argument("--cores", type=int, default=2)
    e.set_defaults(func=estimate)
    s = sub.add_parser("stiffness", help="steady state, early transient, overlap and cost against kappa")
    src = s.add_mutually_exclusive_group(required=True)
    src.add_argument("--cases", nargs="+",
                     help="case folders (pre-shear and heaviside run, scene.json; any setting, grouped by it)")
    src.add_argument("--releases", nargs="+",
                     help="data releases of such cases (data/stiffness-*): each is verified against its "
                          "manifest and its cases restored into a scratch folder; no DEM engine needed")
    s.add_argument("--out", required=True, help="output folder")
    s.add_argument("--steady-window", type=float, default=0.6, help="pre-shear strain averaged for steady values")
    s.add_argument("--early-strain", type=float, default=0.1, help="strain after the reversal of the early transient")
    s.set_defaults(func=stiffness_study)
    g = sub.add_parser("engines", help="YADE against LAMMPS: steady state and early transients within seed noise")
    g.add_argument("--yade", required=True, help="YADE's cases: a folder of case folders (<results_dir>/dem) or a "
                                                 "data release (data/<name> or its cases/)")
    g.add_argument("--lammps", required=True, help="LAMMPS's cases, as --yade")
    g.add_argument("--stage", default="heaviside",
                   help="the reversal stage compared (heaviside, sinusoidal, a schedule)")
    g.add_argument("--out", required=True, help="output folder")
    g.add_argument("--name", default="engines", help="file name prefix: <name>_agreement.csv/.md/.json, "
                                                     "<name>_cost.csv, <name>_transients.png")
    g.add_argument("--yade-cases", default="*", help="only the YADE case folders matching this glob")
    g.add_argument("--lammps-cases", default="*", help="only the LAMMPS case folders matching this glob")
    g.add_argument("--steady-window", type=float, default=None,
                   help="last pre-shear strain of the steady values (default: the last half of the pre-shear)")
    g.add_argument("--early-strain", type=float, default=0.1, help="strain after the reversal compared")
    g.add_argument("--transient-bin", type=float, default=0.01, help="strain bin of the transient curves")
    g.add_argument("--match-se", type=float, default=2.0, help="combined standard errors of an agreement")
    g.set_defaults(func=engines_study)
    args = p.parse_args(argv)
    try:
        return args.func(args)
    except (analysis.StudyInputError, DEMInputError, ValueError) as err:
        print(f"dem_study {args.command}: error: {err}", file=sys.stderr)
        return 2
