"""The pre-flight check: every bad config is named before any job runs.

The Snakefile calls ``check`` right after loading the config and stops with exit
code 2 and one line per problem when it finds any::

    config error: <key> = <value>: <what is wrong> (allowed: <what would do>)

It holds what the schema (``workflow/schemas/config.schema.yaml``) cannot say:
non-finite numbers, keys that must agree with each other (sampling intervals,
bulk band and gap, a protocol's strains), case labels that two values would
share, calibration sets and the sensitivity set naming what the campaign does
not have, extra calibrate / compare options their parsers refuse or the
workflow passes itself (``options``), where the results folder and the releases lie
(``paths``), and duplicated keys in the config file's text (``configfile``: a YAML
loader otherwise lets the last one win). Last, every scene the
campaign would write is checked by yade_scripts' own validator, so nothing the
DEM would refuse reaches its first job, and with ``engine: lammps`` what
lammps_scripts does not run yet is named (``engine_problems``).

``python -m preflight check CONFIGFILE...`` runs the same check outside Snakemake
(it also names a missing or malformed file with its line).
"""
from __future__ import annotations

import math
import re
from pathlib import Path

from campaign import stage_options
from campaign.calibration_sets import calibration_sets, same_value
from campaign.cases import cases, rates
from campaign.configfile import ConfigProblem, configfile_problems, load_configfile  # noqa: F401 (re-exported)
from campaign.scene_spec import inertial_number_range, lammps_refusals, protocol_strain, scene_default, scene_module
from campaign.schema_defaults import SCHEMA, cell_kind, dem_engine, schema as read_schema
from campaign.scenes import scene_from_config
from dem_contract.labels import case_label, format_number

from .options import options_problems
from .paths import release_problems, results_dir_problems
from .problems import problem
from .problems import value_text as _v

ROOT = Path(__file__).resolve().parents[1]

#: Largest inertial number taken as quasi-static (the model's regime, docs/model.md):
#: above it a campaign needs ``loading.allow_inertial: true``.
QUASI_STATIC_MAX_I = 1.0e-2
#: Widest periodic cell (W/H) that YADE's flipCell keeps Lees-Edwards (yade_scripts/scene.py checks it too).
PERIODIC_MAX_W_OVER_H = 1.1
#: Calibration set names are path parts and Snakemake wildcards (workflow/rules/common.smk).
SET_NAME = re.compile(r"^[A-Za-z0-9.-]+(_[A-Za-z0-9.-]+)*$")


# --- values the schema cannot see ------------------------------------------------

def _walk(node, key=""):
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _walk(v, f"{key}.{k}" if key else str(k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _walk(v, f"{key}[{i}]")
    else:
        yield key, node


def finite_problems(config: dict) -> list[str]:
    """NaN or infinity anywhere: the schema's ranges let NaN through (every comparison with it is false)."""
    return [problem(key, value, "must be a finite number")
            for key, value in _walk(config) if isinstance(value, float) and not math.isfinite(value)]


def schema_problems(config: dict, schema_path=SCHEMA) -> list[str]:
    """The schema's findings, one line each, naming the key (Snakemake's validate then fills defaults)."""
    import jsonschema

    schema = read_schema(schema_path)
    validator = jsonschema.validators.validator_for(schema)(schema)
    out = []
    for error in sorted(validator.iter_errors(config), key=lambda e: list(map(str, e.absolute_path))):
        key = "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in error.absolute_path).lstrip(".")
        hint = ""
        if isinstance(error.instance, str) and error.validator == "type":
            try:
                float(error.instance)
                hint = " (YAML reads a number like 1.0e5 as text: write 1.0e+5)"
            except ValueError:
                if error.instance.lower() in ("true", "false") and "boolean" in error.validator_value:
                    hint = f" (snakemake --config reads {error.instance} as text: write {error.instance.title()})"
        if error.validator == "pattern" and "title" in error.schema:   # the pattern in words
            hint = f" (allowed: {error.schema['title']})"
        out.append(f"config error: {key or '<top level>'}: {error.message}{hint}")
    return out


def _seed_problems(seeds, key) -> list[str]:
    return [problem(f"{key}[{i}]", s, "must be an integer (write 1, not 1.0)", "0, 1, 2, ...", shown=repr(s))
            for i, s in enumerate(seeds or []) if isinstance(s, float)]


def loading_problems(config: dict) -> list[str]:
    """Rates within the DEM's range and the quasi-static bound; distinct case labels; integer seeds."""
    loading, out = config["loading"], []
    allow = bool(loading.get("allow_inertial", False))
    i_lo, i_hi = inertial_number_range()
    out += _seed_problems(config["seeds"], "seeds")
    out += _seed_problems((config.get("accuracy") or {}).get("seeds"), "accuracy.seeds")
    for p in loading["pressures"]:
        for j, I in enumerate(rates(config, p)):
            if "wall_velocities" in loading:
                key, value = f"loading.wall_velocities[{j}]", loading["wall_velocities"][j]
                why = f"gives I = {I:.3g} at p = {format_number(p)} Pa (I = 2U/H d/sqrt(p/rho), H = H_over_d d)"
            else:
                key, value, why = f"loading.inertial_numbers[{j}]", I, "I"
            if not i_lo <= I <= i_hi:
                out.append(problem(key, value, f"{why} outside the DEM's range",
                                   f"I in [{i_lo:g}, {i_hi:g}]"))
            elif I > QUASI_STATIC_MAX_I and not allow:
                out.append(problem(key, value, f"{why} is above the quasi-static bound I <= {QUASI_STATIC_MAX_I:g} "
                                   "the model is made for",
                                   f"I <= {QUASI_STATIC_MAX_I:g}, or set loading.allow_inertial: true"))
    if out:
        return out
    # two values that print alike would make one case (and one folder) of two
    by_label = {}
    for p in loading["pressures"]:
        for I in rates(config, p):
            by_label.setdefault(case_label(p, I, config["seeds"][0]), []).append((p, I))
    for label, pairs in by_label.items():
        if len(pairs) > 1:
            (p0, I0), (p1, I1) = pairs[:2]
            key = "loading.pressures" if p0 != p1 else (
                "loading.wall_velocities" if "wall_velocities" in loading else "loading.inertial_numbers")
            values = f"{p0!r} and {p1!r}" if p0 != p1 else f"{I0!r} and {I1!r}"
            out.append(problem(key, None, f"both give the case label {label} (labels keep 6 significant digits), "
                               "so the two would be one case", "values that differ within 6 significant digits", shown=values))
    return out


def cell_problems(config: dict) -> list[str]:
    """Sampling intervals in order, a bulk band inside the gap, a width for 3 disks, a packing that can compress,
    disks of more than one size."""
    out = []
    s, cell, mat, pack = config["sampling"], config["cell"], config["material"], config.get("pack") or {}
    if mat["size_ratio_min"] >= mat["size_ratio_max"]:   # the schema allows 1 and 1 (min <= 1 <= max)
        out.append(problem("material.size_ratio_min", mat["size_ratio_min"],
                           f"equals material.size_ratio_max = {_v(mat['size_ratio_max'])}: disks of one size pack "
                           "in 2D into a crystal (hexagonal order), not the disordered packing the model and the "
                           "paper are about", "size_ratio_min < size_ratio_max (paper: 0.5 and 1.5)"))
    if s["fine_interval"] > s["coarse_interval"]:
        out.append(problem("sampling.fine_interval", s["fine_interval"],
                           f"is above sampling.coarse_interval = {_v(s['coarse_interval'])}",
                           "fine_interval <= coarse_interval"))
    periodic = cell_kind(config) == "periodic"
    if not periodic:
        out += _bulk_problems(cell["H_over_d"], s.get("bulk_exclusion_d", scene_default("sampling", "bulk_exclusion_d")),
                              "the gap cell.H_over_d")
    elif cell["W_over_H"] > PERIODIC_MAX_W_OVER_H:
        out.append(problem("cell.W_over_H", cell["W_over_H"],
                           "is too wide for a periodic cell (YADE flips the sheared cell by whole periods, "
                           "which mixes the axes of a cell wider than about 1.15 times its height)",
                           f"W_over_H <= {PERIODIC_MAX_W_OVER_H:g} with cell.kind = periodic"))
    if not periodic and "mass" in cell:
        out.append(problem("cell.mass", cell["mass"], "applies to a periodic cell only (the wall's mass is its disks')",
                           "leave it out, or set cell.kind: periodic"))
    W = cell["W_over_H"] * cell["H_over_d"]
    if W < 3 * mat["size_ratio_max"]:
        out.append(problem("cell.W_over_H", cell["W_over_H"],
                           f"the periodic width {W:g} d cannot hold 3 of the largest disks "
                           f"({_v(mat['size_ratio_max'])} d)", f"W_over_H >= {3 * mat['size_ratio_max'] / cell['H_over_d']:.3g}"))
    phi0 = pack.get("initial_solid_fraction", scene_default("pack", "initial_solid_fraction"))
    phi = pack.get("solid_fraction_guess", scene_default("pack", "solid_fraction_guess"))
    if phi0 >= phi:
        out.append(problem("pack.initial_solid_fraction", phi0,
                           f"must be below pack.solid_fraction_guess = {_v(phi)} (the loose placement is compressed to it)",
                           f"< {_v(phi)}"))
    return out


def loading_rate_problems(config: dict) -> list[str]:
    """A loading with no rate names the two keys that give one (the schema's oneOf names neither)."""
    loading = config.get("loading")
    if not isinstance(loading, dict) or "inertial_numbers" in loading or "wall_velocities" in loading:
        return []
    return [problem("loading", None, "gives no shear rate", "loading.inertial_numbers (a list of I) or "
                    "loading.wall_velocities (a list of wall speeds in m/s), one of the two",
                    shown="no inertial_numbers, no wall_velocities")]


#: Keys a periodic cell has no use for (yade_scripts/scene.py ``WALL_ONLY``): the scene file would drop them.
WALL_ONLY_KEYS = (("sampling", "bulk_exclusion_d"),)


def periodic_cell_key_problems(config: dict) -> list[str]:
    """A wall cell's key given to a periodic cell is an error, as ``cell.mass`` given to a wall cell is."""
    if cell_kind(config) != "periodic":
        return []
    return [problem(f"{section}.{key}", config[section][key],
                    "applies to a wall cell only (a periodic cell has no wall layers to leave out)",
                    "leave it out, or set cell.kind: walls")
            for section, key in WALL_ONLY_KEYS if key in (config.get(section) or {})]


def _bulk_problems(H_over_d, bulk, gap):
    if H_over_d - 2 * bulk < 1:
        return [problem("sampling.bulk_exclusion_d", bulk,
                        f"two bands of {_v(bulk)} d leave no bulk in {gap} = {_v(H_over_d)}",
                        f"bulk_exclusion_d <= {(H_over_d - 1) / 2:g} (H_over_d - 2 bulk_exclusion_d >= 1)")]
    return []


def protocol_problems(config: dict) -> list[str]:
    """A protocol longer than its transition, and every stage (every segment) at least one sampling interval long."""
    out, s = [], config["sampling"]
    after_reversal = s["fine_interval"] if s["fine_window"] > 0 else s["coarse_interval"]
    sin = config["protocols"].get("sinusoidal")
    if sin and sin["transition_strain"] > sin["strain"]:
        out.append(problem("protocols.sinusoidal.transition_strain", sin["transition_strain"],
                           f"is longer than protocols.sinusoidal.strain = {_v(sin['strain'])}: "
                           "the run would stop inside the half cosine",
                           f"transition_strain <= {_v(sin['strain'])}"))
    for name, spec in config["protocols"].items():
        if "schedule" in spec or "train" in spec:
            keys = ([f"protocols.{name}.schedule[{i}].strain" for i in range(len(spec["schedule"]))]
                    if "schedule" in spec else [f"protocols.{name}.train.every"])
            values = [seg["strain"] for seg in spec["schedule"]] if "schedule" in spec else [spec["train"]["every"]]
            if "schedule" in spec and all(seg["direction"] == 1 for seg in spec["schedule"]):
                out.append(problem(f"protocols.{name}.schedule[*].direction", None,
                                   "no reversal: every segment has direction +1 (the pre-shear's)",
                                   "at least one segment with direction -1",
                                   shown=str([seg["direction"] for seg in spec["schedule"]])))
            for i, (seg, lim) in enumerate(zip(spec.get("schedule") or [spec["train"]], values)):
                if seg.get("transition_strain", 0.0) > lim:
                    out.append(problem(keys[i].rsplit(".", 1)[0] + ".transition_strain", seg["transition_strain"],
                                       f"is longer than {keys[i]} = {_v(lim)}: the half cosine would not end",
                                       f"transition_strain <= {_v(lim)}"))
            for key, value in zip(keys, values):
                if value < after_reversal:
                    out.append(problem(key, value, f"shorter than one sample ({_v(after_reversal)} of strain "
                                       "after a reversal)", f"strain >= {_v(after_reversal)}"))
            continue
        if spec["strain"] < after_reversal:
            out.append(problem(f"protocols.{name}.strain", spec["strain"],
                               f"shorter than one sample ({_v(after_reversal)} of strain after the reversal)",
                               f"strain >= {_v(after_reversal)}"))
    if config["preshear"]["strain"] < s["coarse_interval"]:
        out.append(problem("preshear.strain", config["preshear"]["strain"],
                           f"shorter than one sample (sampling.coarse_interval = {_v(s['coarse_interval'])})",
                           f"strain >= {_v(s['coarse_interval'])}"))
    return out


def calibrate_min_samples(config: dict, root=ROOT) -> int:
    """Fewest rows calibrate accepts per DEM file: ``--min-samples`` of calibration.options, else its default.

    The default is read from calibrate/io.py's ``MIN_SAMPLES = ...`` line (importing
    calibrate costs seconds at every Snakemake start).
    """
    import ast

    given = stage_options.given(stage_options.words(config, "calibration.options")).get("--min-samples")
    if given:
        return int(given[0])  # (checked by options_problems before)
    tree = ast.parse((Path(root) / "calibrate" / "io.py").read_text())
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "MIN_SAMPLES" for t in node.targets):
            return int(ast.literal_eval(node.value))
    from calibrate.io import MIN_SAMPLES

    return MIN_SAMPLES


def expected_rows(strain: float, fine_strain: float, sampling: dict) -> int:
    """Rows a stage writes: one per fine_interval over its first ``fine_strain``, one per coarse_interval after.

    yade_scripts/stages.py samples finely over the transition plus ``sampling.fine_window``
    from the start of every shear stage, then coarsely.
    """
    fine = min(strain, fine_strain)
    return int(fine / sampling["fine_interval"] + max(strain - fine, 0.0) / sampling["coarse_interval"]) + 1


def sample_count_problems(config: dict, root=ROOT) -> list[str]:
    """Every shear stage long enough for the rows calibrate needs per file."""
    need = calibrate_min_samples(config, root)
    s, out = config["sampling"], []
    runs = [("preshear.strain", config["preshear"]["strain"], s["fine_window"])]
    for name, spec in config["protocols"].items():
        if "schedule" in spec or "train" in spec:   # one file: its whole strain (a lower bound of its rows)
            runs.append((f"protocols.{name} (its segments' strain)", protocol_strain(name, spec), s["fine_window"]))
            continue
        runs.append((f"protocols.{name}.strain", spec["strain"], spec.get("transition_strain", 0.0) + s["fine_window"]))
    for key, strain, fine_strain in runs:
        rows = expected_rows(strain, fine_strain, s)
        if rows < need:
            out.append(problem(key, strain, f"gives about {rows} samples with this sampling: calibrate needs "
                               f"{need} per file (its --min-samples)",
                               "a longer strain, finer sampling, or --min-samples in calibration.options"))
    return out


def calibration_problems(config: dict) -> list[str]:
    """Calibration sets that name what the campaign has; a sensitivity set that exists."""
    out = []
    table = cases(config)
    pressures = sorted({c["pressure"] for c in table.values()})
    inertial = sorted({c["inertial_number"] for c in table.values()})
    protocols = list(config["protocols"])
    sets = (config.get("calibration") or {}).get("sets") or {}
    for name, spec in sets.items():
        key = f"calibration.sets.{name}"
        if not SET_NAME.match(str(name)):
            out.append(problem(key, name, "is not a usable set name (it names a folder and a Snakemake wildcard)",
                               "letters, digits, '.', '-', single '_' between them"))
            continue
        for field, have in (("pressures", pressures), ("inertial_numbers", inertial)):
            for i, v in enumerate(spec.get(field) or []):
                if not any(same_value(v, h) for h in have):
                    out.append(problem(f"{key}.{field}[{i}]", v, "is not in the campaign, so the set would "
                                       "silently lose it", ", ".join(format_number(h) for h in have)))
        for i, seed in enumerate(spec.get("seeds") or []):
            if seed not in config["seeds"]:
                out.append(problem(f"{key}.seeds[{i}]", seed, "is not a seed of the campaign (seeds:), so the set "
                                   "would silently lose it", ", ".join(str(s) for s in config["seeds"])))
        for i, p in enumerate(spec.get("protocols") or []):
            if p not in protocols:
                out.append(problem(f"{key}.protocols[{i}]", p, "is not a protocol of the campaign (protocols:)",
                                   ", ".join(protocols)))
    if out:
        return out
    built = calibration_sets(config, table)
    for name in sets:
        if name not in built:
            out.append(problem(f"calibration.sets.{name}", name, "selects no case of the campaign"))
    sensitivity = (config.get("compare") or {}).get("sensitivity_set", "all")
    if sensitivity not in built:
        out.append(problem("compare.sensitivity_set", sensitivity, "is not a calibration set",
                           ", ".join(sorted(built))))
    return out


def study_problems(config: dict) -> list[str]:
    """The DEM study's grid (when it runs): dem_study.grid's own checks, bulk band and width per height."""
    acc = config.get("accuracy") or {}
    if not acc.get("dem_study", False):
        return []
    from dem_study import grid

    try:
        points = grid.unique_points(grid.expand(acc))
    except (ValueError, KeyError) as exc:
        return [f"config error: {str(exc).strip(chr(39))}"]
    if cell_kind(config) == "periodic":
        return []
    bulk = config["sampling"].get("bulk_exclusion_d", scene_default("sampling", "bulk_exclusion_d"))
    out = []
    for H in sorted(set(points["H_over_d"])):
        out += _bulk_problems(H, bulk, "the DEM study's gap accuracy H_over_d")
    return out


def scene_problems(config: dict, root=ROOT) -> list[str]:
    """Every scene the campaign (and the DEM study) would write, through the DEM's own validator."""
    module = scene_module(root)
    validate, SceneError = module.validate, module.SceneError
    scenes = [(label, scene_from_config(config, case, label)) for label, case in cases(config).items()]
    if (config.get("accuracy") or {}).get("dem_study", False):
        from dem_study import grid

        scenes += [(point, grid.point_scene(config, point))
                   for point in grid.unique_points(grid.expand(config["accuracy"]))["point"]]
    out = []
    for label, scene in scenes:
        try:
            validate(scene)
        except SceneError as exc:
            line = f"config error: the scene of {label}: {str(exc).removeprefix('scene error: ')}"
            if line not in out:
                out.append(line)
    return out


def engine_problems(config: dict, root=ROOT) -> list[str]:
    """With ``engine: lammps``, what lammps_scripts does not run (lammps_scripts/refusals.py), by key:
    the bulk-vs-walls study (its periodic cells) and every scene setting it refuses. Every protocol
    runs (heaviside, sinusoidal, every schedule and train)."""
    if dem_engine(config) != "lammps":
        return []
    mod = lammps_refusals(root)
    out = []
    if ((config.get("accuracy") or {}).get("bulk_vs_walls") or {}).get("run", False):
        out.append(problem("accuracy.bulk_vs_walls.run", True, "the bulk-vs-walls study's periodic cells "
                           "run in yade only", "false, or engine: yade"))
    label, case = next(iter(cases(config).items()))
    for why in mod.refusals(scene_module(root).validate(scene_from_config(config, case, label))):
        out.append(f"config error: engine = 'lammps' cannot run {why}")
    return out


def _schedule_hint(line: str, config: dict) -> str:
    """A schema line about a protocol that is neither heaviside, sinusoidal nor a schedule: say what it could be."""
    protocols = config.get("protocols") if isinstance(config.get("protocols"), dict) else {}
    for name, spec in protocols.items():
        if (name not in ("heaviside", "sinusoidal") and line.startswith(f"config error: protocols.{name}: ")
                and not (isinstance(spec, dict) and {"schedule", "train"} & set(spec))):
            return (line + " (a protocol other than heaviside and sinusoidal is a reversal schedule: "
                    "{schedule: [segments]} or {train: {every, reversals}}, docs/scene.md)")
    return line


def check(config: dict, configfiles=(), schema_path=SCHEMA, root=ROOT) -> list[str]:
    """Every problem of the config, one line each; empty when the campaign may start.

    Parameters
    ----------
    config : dict
        The config as Snakemake holds it (files and ``--config`` merged), before
        the schema's defaults are filled in.
    configfiles : list of paths
        The config files it came from, checked for duplicated keys.
    """
    out = configfile_problems(configfiles)
    if "loading" in config and isinstance(config["loading"], dict):
        if "inertial_numbers" in config["loading"] and "wall_velocities" in config["loading"]:
            out.append("config error: loading: give inertial_numbers or wall_velocities, not both")
    rate = loading_rate_problems(config)
    out += rate + finite_problems(config)
    # (the "not both" and "no rate" lines say what the schema's oneOf says at length, or without the keys)
    out += [_schedule_hint(line, config) for line in schema_problems(config, schema_path)
            if not (out and line.startswith("config error: loading: {") and "is valid under each of" in line)
            and not (rate and line.startswith("config error: loading: {") and "not valid under any of" in line)]
    if out:
        return out
    out += results_dir_problems(config, root) + release_problems(config, root)
    for step in (loading_problems, cell_problems, periodic_cell_key_problems,
                 protocol_problems, calibration_problems, options_problems, study_problems):
        out += step(config)
    if not out:
        out += sample_count_problems(config, root)  # (needs intervals in order and valid options)
    return out or scene_problems(config, root) or engine_problems(config, root)


def stop_on_problems(problems: list[str]) -> None:
    """Print the problems on stderr and exit with code 2 (bad input), before Snakemake plans any job."""
    import sys

    if problems:
        print("\n".join(problems), file=sys.stderr, flush=True)
        sys.exit(2)

