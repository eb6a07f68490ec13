"""The parameter file that ``calibrate`` writes and ``model`` reads.

Format (YAML, one document; every block required unless marked optional)::

    format: fabric-friction-params      # fixed tag
    version: 2                          # 1: read as well (files written before the end line)
    friction_eq2:       {X0: 0.028, k1: 2.7, k3: 20.0, k5: 90000.0}   # Eq. 2
    friction_quadratic: {m0: 0.0, m1: -3.3, m2: 0.0}                  # law of [15]
    model1: {a1: ..., b1: ..., c1: ..., a2: ..., b2: ..., c2: ..., X_c: 0.0827}  # Eq. 6
    model2: {c1: ..., c2: ..., c3: ...}                               # Eq. 5
    intervals:    # optional: {block: {name: [low, high]}} (e.g. bootstrap 95 %)
    provenance:   # optional, free-form: cases, seeds, settings, date
    ...           # version 2: YAML's document end, the file's last line

Every value is dimensionless. ``load_params`` rejects a missing block, a
missing or unknown key, or a value outside ``RANGES`` with a ``ValueError``
that names the key and its allowed range, and a version-2 file whose last
line is not the document end ``...``: a file cut short (a copy or a write
interrupted) still parses as YAML and may hold every required block, with a
value cut (``c3: -33.`` for ``-33.7``) and the intervals and provenance lost.
``save_params`` (the calibration's writer) writes version 2. Version 1
(no end line) is read as before: files written before version 2, and hand-written ones.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path

import yaml

FORMAT_TAG = "fabric-friction-params"
#: The version ``save_params`` writes; ``READ_VERSIONS`` are read.
FORMAT_VERSION = 2
READ_VERSIONS = (1, 2)
#: A version-2 file's last line: YAML's document end (``yaml.safe_dump(..., explicit_end=True)``).
DOCUMENT_END = "..."
#: The top-level blocks ``save_params`` writes, in order (intervals and provenance when not empty).
WRITTEN_BLOCKS = ("friction_eq2", "friction_quadratic", "model1", "model2", "intervals", "provenance")

# Allowed open ranges (low, high) per block and key. Wide on purpose: they
# catch typos and sign slips, not physics (the calibration decides that).
RANGES = {
    "friction_eq2": {"X0": (-0.5, 0.5), "k1": (0.0, 1e3), "k3": (-1e6, 1e6), "k5": (-1e12, 1e12)},
    "friction_quadratic": {"m0": (-10.0, 10.0), "m1": (-1e3, 1e3), "m2": (-1e5, 1e5)},
    "model1": {
        "a1": (-1e3, 1e3), "b1": (-1e5, 1e5), "c1": (-1e9, 1e9),
        "a2": (-1e3, 1e3), "b2": (-1e5, 1e5), "c2": (-1e9, 1e9),
        "X_c": (0.0, 1.0),
    },
    "model2": {"c1": (-1e3, 1e3), "c2": (-1e3, 1e3), "c3": (-1e5, 1e5)},
}


@dataclass(frozen=True)
class FrictionEq2:
    """Eq. 2: mu(X) with y = X - X0 (see ``laws.friction_eq2``)."""

    X0: float
    k1: float
    k3: float
    k5: float


@dataclass(frozen=True)
class FrictionQuadratic:
    """Law of [15]: mu = m0 + m1 X + m2 X^2."""

    m0: float
    m1: float
    m2: float


@dataclass(frozen=True)
class Model1:
    """Eq. 6: alpha_i = a_i + b_i X + [X>0] c_i X^4 / (X_c - X)."""

    a1: float
    b1: float
    c1: float
    a2: float
    b2: float
    c2: float
    X_c: float


@dataclass(frozen=True)
class Model2:
    """Eq. 5 ([15]): alpha1 = c1, alpha2 = c2 + c3 X."""

    c1: float
    c2: float
    c3: float


BLOCKS = {
    "friction_eq2": FrictionEq2,
    "friction_quadratic": FrictionQuadratic,
    "model1": Model1,
    "model2": Model2,
}


@dataclass(frozen=True)
class ModelParams:
    """Everything the continuum model needs, as read from one parameter file."""

    friction_eq2: FrictionEq2
    friction_quadratic: FrictionQuadratic
    model1: Model1
    model2: Model2
    intervals: dict = field(default_factory=dict)
    provenance: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        out = {"format": FORMAT_TAG, "version": FORMAT_VERSION}
        for name in BLOCKS:
            out[name] = {k: float(v) for k, v in dataclasses.asdict(getattr(self, name)).items()}
        if self.intervals:
            out["intervals"] = self.intervals
        if self.provenance:
            out["provenance"] = self.provenance
        return out


def _check_block(name: str, values, source: str) -> dict:
    ranges = RANGES[name]
    if not isinstance(values, dict):
        raise ValueError(f"{source}: '{name}' must be a mapping of {sorted(ranges)}")
    unknown = set(values) - set(ranges)
    if unknown:
        raise ValueError(f"{source}: unknown key(s) {sorted(unknown)} in '{name}'; allowed: {sorted(ranges)}")
    out = {}
    for key, (low, high) in ranges.items():
        if key not in values:
            raise ValueError(f"{source}: missing key '{name}.{key}' (allowed range ({low:g}, {high:g}))")
        try:
            value = float(values[key])
        except (TypeError, ValueError):
            raise ValueError(f"{source}: '{name}.{key}' = {values[key]!r} is not a number") from None
        if not (math.isfinite(value) and low < value < high):
            raise ValueError(
                f"{source}: '{name}.{key}' = {value!r} is outside the allowed range ({low:g}, {high:g})"
            )
        out[key] = value
    return out


def params_from_dict(data: dict, source: str = "parameters") -> ModelParams:
    """Validate a parsed parameter document and build ``ModelParams``."""
    if not isinstance(data, dict):
        raise ValueError(f"{source}: expected a mapping at the top level")
    if data.get("format", FORMAT_TAG) != FORMAT_TAG:
        raise ValueError(f"{source}: 'format' must be '{FORMAT_TAG}', got {data.get('format')!r}")
    version = data.get("version", FORMAT_VERSION)
    try:
        known = not isinstance(version, bool) and float(version) in READ_VERSIONS
    except (TypeError, ValueError):
        known = False
    if not known:
        raise ValueError(f"{source}: 'version' must be one of {list(READ_VERSIONS)}, got {version!r}")
    allowed = set(BLOCKS) | {"format", "version", "intervals", "provenance"}
    unknown = set(data) - allowed
    if unknown:
        raise ValueError(f"{source}: unknown top-level key(s) {sorted(unknown)}; allowed: {sorted(allowed)}")
    blocks = {}
    for name, cls in BLOCKS.items():
        if name not in data:
            raise ValueError(f"{source}: missing block '{name}' with keys {sorted(RANGES[name])}")
        blocks[name] = cls(**_check_block(name, data[name], source))
    return ModelParams(
        **blocks,
        intervals=dict(data.get("intervals") or {}),
        provenance=dict(data.get("provenance") or {}),
    )


def read_yaml(path, what: str = "file"):
    """Parse one YAML document from ``path``.

    Raises
    ------
    ValueError
        One line naming the file and the problem: not found, a directory,
        unreadable, or malformed YAML (with the line and column of yaml's
        ``problem_mark``, counted from 1).
    """
    path = Path(path)
    return _parse_yaml(_read_text(path, what), path, what)


def _read_text(path: Path, what: str) -> str:
    if not path.exists():
        raise ValueError(f"{path}: {what} not found")
    if path.is_dir():
        raise ValueError(f"{path}: is a directory, expected a {what} (YAML)")
    try:
        return path.read_text()
    except (OSError, UnicodeDecodeError) as exc:
        raise ValueError(f"{path}: cannot read the {what} ({exc})") from None


def _parse_yaml(text: str, path: Path, what: str):
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"{path}:{mark.line + 1}:{mark.column + 1}" if mark is not None else str(path)
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise ValueError(f"{where}: malformed YAML in the {what}: {problem}") from None


def load_params(path) -> ModelParams:
    """Read and validate a parameter file (YAML; JSON is valid YAML too).

    Raises
    ------
    ValueError
        Naming the file (and the line, for malformed YAML, or the key).
    """
    path = Path(path)
    text = _read_text(path, "parameter file")
    data = _parse_yaml(text, path, "parameter file")
    check_complete(text, data, path)
    return params_from_dict(data, source=str(path))


def check_complete(text: str, data, path) -> None:
    """A version-2 parameter file ends with its document end line ``...`` (``DOCUMENT_END``).

    Raises
    ------
    ValueError
        Naming the file, where it ends and the blocks of ``WRITTEN_BLOCKS`` it
        lacks: the file was cut short.
    """
    if not isinstance(data, dict) or data.get("version") != FORMAT_VERSION:
        return
    lines = text.rstrip().splitlines()
    if lines and lines[-1] == DOCUMENT_END:
        return
    absent = [b for b in WRITTEN_BLOCKS if b not in data]
    raise ValueError(f"{path}: cut short: a version-{FORMAT_VERSION} parameter file ends with the line "
                     f"'{DOCUMENT_END}', this one at byte {len(text.encode())} after line {len(lines)} "
                     f"{(lines[-1] if lines else '')!r}; what followed is missing"
                     + (f" (absent blocks: {', '.join(absent)})" if absent else "")
                     + "; rerun the calibration or restore the file")


def save_params(params: ModelParams, path) -> None:
    """Write ``params`` in the documented format (round-trips through ``load_params``)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w") as fh:
        yaml.safe_dump(params.to_dict(), fh, sort_keys=False, explicit_end=True)


# Documented defaults: Eq. 2 is our reading of the paper (docs/model.md); the rest is a plausible
# set chosen by hand (see model/README.md) until calibration writes a real file.
DEFAULT_PARAMS_YAML = """\
format: fabric-friction-params
version: 1
friction_eq2: {X0: 0.028, k1: 2.7, k3: 20.0, k5: 90000.0}     # docs/model.md, Eq. 2
friction_quadratic: {m0: 0.0672, m1: -1.29, m2: 24.2}          # least squares to Eq. 2 on X in [-0.075, 0.075]
model1: {a1: -0.3, b1: 0.0, c1: -200.0, a2: -2.0, b2: 25.0, c2: 1000.0, X_c: 0.0827}
model2: {c1: -0.3, c2: -2.0, c3: 25.0}                          # same steady state as model1
provenance: {source: "model.params.DEFAULT_PARAMS_YAML (hand-picked defaults, not calibrated)"}
"""


def default_params() -> ModelParams:
    """The documented default parameters (``DEFAULT_PARAMS_YAML``)."""
    return params_from_dict(yaml.safe_load(DEFAULT_PARAMS_YAML), source="DEFAULT_PARAMS_YAML")
