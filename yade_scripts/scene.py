"""Load and validate a scene file (see docs/scene.md). Pure Python: no YADE import.

Every key is checked once, here, before anything is built: a missing required
key, an unknown key, a wrong type or a value out of range raises SceneError
whose message names the key.
"""
import hashlib
import json
import math
import re

INF = float("inf")
REQUIRED = object()
STAGES = ("pack", "preshear", "heaviside", "sinusoidal")
# The DEM engine that runs the scene: yade_scripts/ (the default and the reference) or lammps_scripts/.
ENGINES = ("yade", "lammps")
ENGINE = "engine"


class SceneError(ValueError):
    pass


def _num(lo, hi, lo_open=False, hi_open=False, integer=False):
    return dict(kind="int" if integer else "num", lo=lo, hi=hi, lo_open=lo_open, hi_open=hi_open)


# section -> key -> (spec, default); default REQUIRED means the key must be given
SPEC = {
    "geometry": {
        "H_over_d": (_num(4, 200), REQUIRED),
        "W_over_H": (_num(0.5, 20), REQUIRED),
    },
    "material": {
        "diameter": (_num(0, 1, lo_open=True), REQUIRED),
        "density": (_num(0, 1e5, lo_open=True), REQUIRED),
        "pressure": (_num(0, 1e9, lo_open=True), REQUIRED),
        "kappa": (_num(100, 1e7), REQUIRED),
        "kt_over_kn": (_num(0, 1, lo_open=True), REQUIRED),
        "restitution": (_num(0, 1, lo_open=True, hi_open=True), REQUIRED),
        "friction": (_num(0, 2), REQUIRED),
        "size_ratio_min": (_num(0, 1, lo_open=True), REQUIRED),
        "size_ratio_max": (_num(1, 3), REQUIRED),
        "contact_law": (dict(kind="choice", choices=("viscel", "frictvisco")), None),
    },
    "loading": {
        "inertial_number": (_num(1e-5, 0.1), REQUIRED),
    },
    "timestep": {
        "dt_over_tc": (_num(0, 0.3, lo_open=True), REQUIRED),
    },
    "pack": {
        "initial_solid_fraction": (_num(0.05, 0.7), 0.55),
        "solid_fraction_guess": (_num(0.5, 0.9), 0.8),
        "ke_max": (_num(0, 1, lo_open=True), 1e-7),
        "wall_speed_max": (_num(0, 1, lo_open=True), 1e-3),
        "pressure_tolerance": (_num(0, 1, lo_open=True), 0.02),
        "compaction_pressure": (_num(0, 1, lo_open=True), 0.5),
        "ramp_time": (_num(0, 1e5), 3.0),
        "check_interval": (_num(0, 1e3, lo_open=True), 0.5),
        "max_time": (_num(0, 1e6, lo_open=True), 2000.0),
        "friction": (dict(_num(0, 2), null=True), None),  # None: material.friction
        "damping": (_num(0, 1, hi_open=True), 0.5),
        "quench": (dict(kind="bool"), True),
    },
    "preshear": {
        "strain": (_num(0, 100, lo_open=True), REQUIRED),
    },
    "heaviside": {
        "strain": (_num(0, 100, lo_open=True), REQUIRED),
    },
    "sinusoidal": {
        "strain": (_num(0, 100, lo_open=True), REQUIRED),
        "transition_strain": (_num(0, 10, lo_open=True), REQUIRED),
    },
    "sampling": {
        "fine_interval": (_num(0, 0.01, lo_open=True), REQUIRED),
        "fine_window": (_num(0, 10), REQUIRED),
        "coarse_interval": (_num(0, 0.1, lo_open=True), REQUIRED),
        "bulk_exclusion_d": (_num(0, 20), 3.0),
    },
    "effects": {
        "gravity": (dict(kind="gravity"), False),
        "damping": (_num(0, 1, hi_open=True), 0.0),
        "rolling_resistance": (_num(0, 1), 0.0),
        "measurements": (dict(kind="bool"), True),
    },
    "cell": {
        "kind": (dict(kind="choice", choices=("walls", "periodic")), "walls"),
        "mass": (_num(0, 1, lo_open=True), 1.0),  # 10 was measured unstable (p swung 0.45-1.6)
    },
    "run": {
        "checkpoint_every_s": (_num(1, 1e5), 600.0),
        "progress_every_s": (_num(0.1, 1e5), 30.0),
    },
    "guards": {
        "max_overlap_d": (_num(0, 0.5, lo_open=True), 0.05),
        "pressure_tolerance": (_num(0, 10, lo_open=True), 0.2),
        "pressure_window_strain": (_num(0, 100, lo_open=True), 0.1),
        "pressure_noise_z": (_num(0, 100), 2.5),
    },
}
# sections that may be left out entirely (all keys have defaults, or only some stages need them)
OPTIONAL_SECTIONS = {"pack", "effects", "run", "guards", "heaviside", "sinusoidal", "cell"}
# keys that only one cell kind uses: given explicitly for the other kind, they are an error
WALL_ONLY = ("sampling.bulk_exclusion_d",)
PERIODIC_ONLY = ("cell.mass",)
STAGE_SECTIONS = {"heaviside": "heaviside", "sinusoidal": "sinusoidal"}

# ---------------------------------------------------------------- reversal schedules
# A schedule is a protocol of its own name, kept in the scene's `schedules` section:
#   {"schedule": [{"strain": 0.2, "direction": -1, "transition": "heaviside"}, ...]}
#   {"train": {"every": 0.2, "reversals": 6, "transition": "heaviside"}}
# Directions are relative to the pre-shear (+1 its direction, -1 reversed); a segment
# starts with a reversal when its direction differs from the one before it (the
# pre-shear's for the first segment). A segment's strain is its duration as strain at
# the nominal rate (time x gammadot), a half-cosine transition included.
SCHEDULES = "schedules"
PROTOCOL_NAME = re.compile(r"^[a-z][a-z0-9_]*$")
RESERVED_NAMES = ("pack", "preshear", "scene", "final", "campaign_summary")
TRANSITIONS = ("heaviside", "half_cosine")
SEGMENT_SPEC = {
    "strain": (_num(0, 100, lo_open=True), REQUIRED),
    "direction": (dict(kind="direction"), REQUIRED),
    "transition": (dict(kind="choice", choices=TRANSITIONS), "heaviside"),
    "transition_strain": (_num(0, 10, lo_open=True), None),
}
TRAIN_SPEC = {
    "every": (_num(0, 100, lo_open=True), REQUIRED),
    "reversals": (_num(1, 1000, integer=True), REQUIRED),
    "transition": (dict(kind="choice", choices=TRANSITIONS), "heaviside"),
    "transition_strain": (_num(0, 10, lo_open=True), None),
}
MAX_SEGMENTS = 1000


def _fmt_range(s):
    lo = "(" if s["lo_open"] else "["
    hi = ")" if s["hi_open"] else "]"
    return f"{lo}{s['lo']:g}, {s['hi']:g}{hi}"


def _check_value(name, spec, v):
    kind = spec["kind"]
    if v is None and spec.get("null"):
        return None
    if kind == "choice":
        if v not in spec["choices"]:
            raise SceneError(f"scene error: {name} = {v!r} must be one of {', '.join(spec['choices'])}")
        return v
    if kind == "direction":
        if isinstance(v, bool) or v not in (-1, 1):
            raise SceneError(f"scene error: {name} = {v!r} must be -1 (against the pre-shear) or +1 (with it)")
        return int(v)
    if kind == "bool":
        if not isinstance(v, bool):
            raise SceneError(f"scene error: {name} = {v!r} must be true or false")
        return v
    if kind == "gravity":
        if v is False or v is None:
            return False
        if (isinstance(v, list) and len(v) in (2, 3)
                and all(isinstance(x, (int, float)) and not isinstance(x, bool)
                        and math.isfinite(x) for x in v)):
            if len(v) == 3 and v[2] != 0:
                raise SceneError(f"scene error: {name} = {v!r}: the z component must be 0 (disks in the xy plane)")
            if all(x == 0 for x in v):
                return False
            return [float(v[0]), float(v[1])]
        raise SceneError(f"scene error: {name} = {v!r} must be false or [gx, gy] in m/s^2")
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise SceneError(f"scene error: {name} = {v!r} must be a number")
    if kind == "int" and not (isinstance(v, int) or float(v).is_integer()):
        raise SceneError(f"scene error: {name} = {v!r} must be an integer")
    if not math.isfinite(v):
        raise SceneError(f"scene error: {name} = {v!r} must be finite")
    lo_bad = v <= spec["lo"] if spec["lo_open"] else v < spec["lo"]
    hi_bad = v >= spec["hi"] if spec["hi_open"] else v > spec["hi"]
    if lo_bad or hi_bad:
        raise SceneError(f"scene error: {name} = {v!r} is out of range {_fmt_range(spec)}")
    return int(v) if kind == "int" else float(v)


def validate(raw, stage=None):
    """Return the scene with defaults filled in; raise SceneError naming the bad key.

    stage: if given, the sections that stage needs must be present.
    """
    if not isinstance(raw, dict):
        raise SceneError("scene error: the scene must be a JSON object")
    known = set(SPEC) | {"seed", "meta", SCHEDULES, ENGINE}
    for k in raw:
        if k not in known:
            raise SceneError(f"scene error: unknown key '{k}' (allowed: {', '.join(sorted(known))})")
    out = {}
    if "seed" not in raw:
        raise SceneError("scene error: missing required key 'seed'")
    out["seed"] = _check_value("seed", _num(0, 2**31 - 1, integer=True), raw["seed"])
    meta = raw.get("meta", {})
    if not isinstance(meta, dict):
        raise SceneError("scene error: meta must be a JSON object")
    out["meta"] = meta
    for sec, keys in SPEC.items():
        if sec not in raw:
            if sec in OPTIONAL_SECTIONS:
                if stage is not None and STAGE_SECTIONS.get(stage) == sec:
                    raise SceneError(f"scene error: missing section '{sec}' needed by stage {stage}")
                if sec in STAGE_SECTIONS.values():
                    continue
                src = {}
            else:
                raise SceneError(f"scene error: missing required section '{sec}'")
        else:
            src = raw[sec]
        if not isinstance(src, dict):
            raise SceneError(f"scene error: section '{sec}' must be a JSON object")
        out[sec] = _check_keys(sec, src, keys)
    if ENGINE in raw:  # (absent: YADE, and the validated scene stays as it was before engines existed)
        out[ENGINE] = _check_value(ENGINE, dict(kind="choice", choices=ENGINES), raw[ENGINE])
    if SCHEDULES in raw:  # (absent: the validated scene stays as it was before schedules existed)
        out[SCHEDULES] = check_schedules(raw[SCHEDULES])
    if stage is not None and stage not in STAGES and stage not in out.get(SCHEDULES, {}):
        raise SceneError(f"scene error: stage {stage!r} is neither one of {', '.join(STAGES)} nor a schedule of "
                         f"the scene's '{SCHEDULES}' section ({', '.join(out.get(SCHEDULES, {})) or 'none'})")
    _check_cell_kind(raw, out["cell"]["kind"])
    _check_contact_law(out)
    # cross-key checks
    m, s = out["material"], out["sampling"]
    if s["coarse_interval"] < s["fine_interval"]:
        raise SceneError("scene error: sampling.coarse_interval must be >= sampling.fine_interval")
    H = out["geometry"]["H_over_d"]
    if H - 2 * s["bulk_exclusion_d"] < 1:
        raise SceneError(
            f"scene error: sampling.bulk_exclusion_d = {s['bulk_exclusion_d']:g} leaves no bulk band "
            f"(needs H_over_d - 2*bulk_exclusion_d >= 1, H_over_d = {H:g})")
    W = out["geometry"]["W_over_H"] * H
    if out["cell"]["kind"] == "periodic" and out["geometry"]["W_over_H"] > 1.1:
        # YADE's flipCell keeps a sheared cell Lees-Edwards (only the top edge shifts by W) only if
        # W <= 1.15 L_y; a wider cell gets its axes mixed at the first flip
        raise SceneError(f"scene error: geometry.W_over_H = {out['geometry']['W_over_H']:g} is out of range "
                         f"[0.5, 1.1] for cell.kind = periodic (the sheared cell is flipped by whole periods)")
    if W < 3 * m["size_ratio_max"]:
        raise SceneError("scene error: geometry.W_over_H too small: the periodic width must hold 3 of the largest disks")
    if out["pack"]["initial_solid_fraction"] >= out["pack"]["solid_fraction_guess"]:
        raise SceneError("scene error: pack.initial_solid_fraction must be below pack.solid_fraction_guess")
    return out


def _check_keys(name, src, spec):
    """Check one JSON object against a key -> (spec, default) table; return it with defaults filled in."""
    if not isinstance(src, dict):
        raise SceneError(f"scene error: {name} must be a JSON object")
    for k in src:
        if k not in spec:
            raise SceneError(f"scene error: unknown key '{name}.{k}' (allowed: {', '.join(spec)})")
    o = {}
    for k, (sp, default) in spec.items():
        if k in src:
            o[k] = _check_value(f"{name}.{k}", sp, src[k])
        elif default is REQUIRED:
            raise SceneError(f"scene error: missing required key '{name}.{k}'")
        else:
            o[k] = default
    return o


def _check_transition(name, o, length_key):
    """transition_strain: required by a half cosine (and within the segment), refused otherwise."""
    if o["transition"] == "half_cosine":
        if o["transition_strain"] is None:
            raise SceneError(f"scene error: missing required key '{name}.transition_strain' "
                             f"(needed by transition = half_cosine; allowed range (0, 10])")
        if o["transition_strain"] > o[length_key]:
            raise SceneError(f"scene error: {name}.transition_strain = {o['transition_strain']!r} is out of range "
                             f"(0, {o[length_key]:g}]: longer than {name}.{length_key}, the half cosine would not end")
    else:
        if o["transition_strain"] is not None:
            raise SceneError(f"scene error: {name}.transition_strain applies to transition = half_cosine only "
                             f"({name}.transition = {o['transition']})")
        del o["transition_strain"]
    return o


def check_schedules(raw):
    """The `schedules` section: name -> {"schedule": [segment, ...]} or {"train": {...}}."""
    if not isinstance(raw, dict):
        raise SceneError(f"scene error: section '{SCHEDULES}' must be a JSON object (name -> schedule)")
    out = {}
    for pname, spec in raw.items():
        where = f"{SCHEDULES}.{pname}"
        if not isinstance(pname, str) or not PROTOCOL_NAME.match(pname) or pname in STAGES + RESERVED_NAMES:
            raise SceneError(f"scene error: {where}: a schedule's name must be lower-case letters, digits and '_', "
                             f"starting with a letter, and not one of {', '.join(STAGES + RESERVED_NAMES)}")
        if not isinstance(spec, dict) or len(spec) != 1 or next(iter(spec)) not in ("schedule", "train"):
            raise SceneError(f"scene error: {where} must hold exactly one of 'schedule' (a list of segments) "
                             f"or 'train' (every, reversals, transition)")
        if "schedule" in spec:
            segs = spec["schedule"]
            if not isinstance(segs, list) or not 1 <= len(segs) <= MAX_SEGMENTS:
                raise SceneError(f"scene error: {where}.schedule must be a list of 1 to {MAX_SEGMENTS} segments")
            checked = [_check_transition(f"{where}.schedule[{i}]",
                                         _check_keys(f"{where}.schedule[{i}]", seg, SEGMENT_SPEC), "strain")
                       for i, seg in enumerate(segs)]
            if all(seg["direction"] == 1 for seg in checked):
                raise SceneError(f"scene error: {where}.schedule has no reversal: every segment has direction +1 "
                                 f"(the pre-shear's); give at least one segment direction -1")
            out[pname] = {"schedule": checked}
        else:
            out[pname] = {"train": _check_transition(f"{where}.train",
                                                     _check_keys(f"{where}.train", spec["train"], TRAIN_SPEC),
                                                     "every")}
    return out


def expand_train(train):
    """The segments of a train: `reversals` segments of `every` strain, directions -1, +1, -1, ..."""
    seg = {"strain": train["every"], "transition": train["transition"]}
    if train["transition"] == "half_cosine":
        seg["transition_strain"] = train["transition_strain"]
    return [dict(seg, direction=-1 if k % 2 == 0 else 1) for k in range(train["reversals"])]


def segments(scene, stage):
    """The segments a reversal stage runs, each {strain, direction, transition[, transition_strain]}.

    heaviside and sinusoidal are one-segment schedules: [{strain, -1, heaviside}] and
    [{strain, -1, half_cosine, transition_strain}].
    """
    if stage == "heaviside":
        return [{"strain": scene["heaviside"]["strain"], "direction": -1, "transition": "heaviside"}]
    if stage == "sinusoidal":
        s = scene["sinusoidal"]
        return [{"strain": s["strain"], "direction": -1, "transition": "half_cosine",
                 "transition_strain": s["transition_strain"]}]
    spec = scene.get(SCHEDULES, {}).get(stage)
    if spec is None:
        raise SceneError(f"scene error: no schedule '{stage}' in the scene's '{SCHEDULES}' section")
    return expand_train(spec["train"]) if "train" in spec else [dict(seg) for seg in spec["schedule"]]


def reversal_strains(segs):
    """Strain at full rate (from the stage's start) at which each reversal starts, with its segment index."""
    out, at, prev = [], 0.0, 1
    for k, seg in enumerate(segs):
        if seg["direction"] != prev:
            out.append((k, at))
        prev = seg["direction"]
        at += seg["strain"]
    return out


def _check_cell_kind(raw, kind):
    """Reject keys of the other cell kind, naming the key (only keys written in the file count)."""
    other = WALL_ONLY if kind == "periodic" else PERIODIC_ONLY
    for name in other:
        sec, k = name.split(".")
        if isinstance(raw.get(sec), dict) and k in raw[sec]:
            owner = "a wall cell" if kind == "periodic" else "a periodic cell"
            raise SceneError(f"scene error: {name} applies to {owner} only (cell.kind = {kind})")


def _check_contact_law(out):
    """Default viscel for a wall cell, frictvisco for a periodic cell; viscel is refused in a periodic cell."""
    m, kind = out["material"], out["cell"]["kind"]
    if m["contact_law"] is None:
        m["contact_law"] = "frictvisco" if kind == "periodic" else "viscel"
    if kind == "periodic" and m["contact_law"] == "viscel":
        raise SceneError(
            "scene error: material.contact_law = 'viscel' cannot be used with cell.kind = periodic: YADE's "
            "Law2_ScGeom_ViscElPhys_Basic adds the periodic image's velocity with the wrong sign, so every "
            "contact across the sheared boundary slides (use frictvisco)")


def engine(scene):
    """The engine that runs the scene: its `engine` key, yade when absent."""
    return scene.get(ENGINE, ENGINES[0])


def load(path, stage=None):
    try:
        with open(path) as f:
            text = f.read()
    except OSError as e:
        raise SceneError(f"scene error: cannot read scene file {path}: {e}")
    try:
        raw = json.loads(text)
    except json.JSONDecodeError as e:
        raise SceneError(f"scene error: {path} is not valid JSON: {e}")
    scene = validate(raw, stage)
    return scene, hashlib.sha256(text.encode()).hexdigest()


def derived(scene):
    """Physical quantities that follow from the scene (SI units)."""
    m, g = scene["material"], scene["geometry"]
    d, rho, p, kappa = m["diameter"], m["density"], m["pressure"], m["kappa"]
    H = g["H_over_d"] * d
    W = g["W_over_H"] * H
    kn = kappa * p * d
    m_d = rho * math.pi * d**2 / 4 * d  # disk of diameter d, thickness d
    tc = math.sqrt(m_d / kn)
    dt = scene["timestep"]["dt_over_tc"] * tc
    T0 = d * math.sqrt(rho / p)  # time unit
    V0 = math.sqrt(p / rho)  # velocity unit
    gd = scene["loading"]["inertial_number"] / T0
    U = gd * H / 2
    smin, smax = m["size_ratio_min"], m["size_ratio_max"]
    D2 = d**2 * (smin**2 + smin * smax + smax**2) / 3  # <D^2> for D uniform
    n_wall = max(3, int(math.floor(W / d + 1e-9)))
    # grains fill the gap between the walls' centre lines less d, or the whole periodic cell
    H_grains = H if scene.get("cell", {}).get("kind") == "periodic" else H - d
    N = int(round(scene["pack"]["solid_fraction_guess"] * W * H_grains / (math.pi * D2 / 4)))
    return dict(d=d, rho=rho, p=p, H=H, W=W, kn=kn, kt=kn * m["kt_over_kn"], m_d=m_d, tc=tc, dt=dt,
                T0=T0, V0=V0, gammadot=gd, U=U, N=N, n_wall=n_wall)
