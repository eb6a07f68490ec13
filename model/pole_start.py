r"""Model 1 with its pole at the start of each reversal (Eq. 6 as the paper configured it).

The paper puts the pole of Eq. 6 at the start of its reversal: ``X_c = 0.0827``
with the steady X of its Eq. 2 near -0.075, so the mirrored X a reversal
starts from sits just below the pole. This variant ("model1_start") takes
that configuration literally, run by run:

.. math:: X_c = \max(X_{rev}, 0) + \delta, \qquad \delta \ge \delta_{min}

- :math:`X_{rev}` is the model's own X at the instant the rate changes sign,
  in the new direction (the mirrored X). A Heaviside run starts reversed, so
  it is the mirrored X of the start fabric, :math:`\sqrt2\,b_0\,g` with g the
  sign after the reversal. A run that first keeps shearing forward (the half
  cosine) is integrated up to its zero of the rate first: there X < 0, where
  Eq. 6 has no pole term, so that part does not depend on X_c and the state
  it reaches is the one the full integration passes through.
- **A start at or past the pole** cannot happen by construction: X_c is set
  from the state the reversal actually starts from, and delta has the lower
  bound ``DELTA_MIN`` > 0, so the start sits at least ``DELTA_MIN`` below the
  pole, where the pole term :math:`c_i X^4/(X_c - X)` is finite. "delta
  profiled down to 0" means down to ``DELTA_MIN``.
- The other parameters (a_i, b_i, c_i) are Model 1's, shared by every run.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import yaml

from .histories import steady_shear
from .params import load_params, params_from_dict

SQRT2 = float(np.sqrt(2.0))
#: Smallest offset of the pole above the start X: the pole term is c_i X^4 / delta at the start.
DELTA_MIN = 1e-4
#: The fitted block of the variant (``calibrate.pole_start_fit``): Eq. 6's a_i, b_i, c_i and delta in place of X_c.
KEYS = ("a1", "b1", "c1", "a2", "b2", "c2", "delta")
FORMAT_TAG = "model1-pole-at-start"
#: A far pole for the forward part before a sinusoidal reversal (X < 0 there: no pole term).
FAR_POLE = 0.99


def mirrored_x(A_xy: float, sign_after: float) -> float:
    r"""X of a fabric sheared with the sign ``sign_after``: :math:`X = \sqrt2\,A_{xy}\,g` (docs/model.md, Sec. 3)."""
    return SQRT2 * float(A_xy) * float(np.sign(sign_after))


def pole_position(x_rev: float, delta: float) -> float:
    r"""X_c of the variant: :math:`\max(X_{rev}, 0) + \max(\delta, \delta_{min})`.

    Raises
    ------
    ValueError
        When ``x_rev`` or ``delta`` is not finite.
    """
    if not (np.isfinite(x_rev) and np.isfinite(delta)):
        raise ValueError(f"pole at start: X_rev = {x_rev!r} and delta = {delta!r} must be finite")
    return max(float(x_rev), 0.0) + max(float(delta), DELTA_MIN)


def with_pole(params, x_rev: float, delta: float):
    """``params`` (``ModelParams``) with Model 1's X_c at ``pole_position(x_rev, delta)``."""
    return dataclasses.replace(params, model1=dataclasses.replace(params.model1, X_c=pole_position(x_rev, delta)))


def far_pole(params):
    """``params`` with Model 1's pole out of reach (``FAR_POLE``): for the forward part before a reversal."""
    return dataclasses.replace(params, model1=dataclasses.replace(params.model1, X_c=FAR_POLE))


def forward_history(strain_before: float, sign_before: float):
    """The forward shear before a reversal, at unit rate (time = strain; Eq. 4 is rate independent)."""
    return steady_shear(float(strain_before), float(np.sign(sign_before)))


def block_params(base_doc: dict, vals: dict):
    """A ``ModelParams``: ``base_doc`` (a parameter document) with ``vals``' a_i, b_i, c_i (X_c set per run later)."""
    d = dict(base_doc)
    d["model1"] = {**{k: vals[k] for k in KEYS if k != "delta"}, "X_c": 0.5}
    return params_from_dict(d, source="pole-at-start parameters")


def load(path) -> tuple:
    """A ``pole_start.yaml`` (``calibrate.pole_start_fit``): (its set's ``ModelParams`` with the variant's a_i, b_i, c_i;
    delta).

    Raises
    ------
    ValueError
        When the file cannot be read or is not such a fit (format tag ``FORMAT_TAG``, the keys ``KEYS``).
    """
    path = Path(path)
    try:
        d = yaml.safe_load(path.read_text())
    except (OSError, yaml.YAMLError) as exc:
        raise ValueError(f"{path}: cannot read the pole-at-start fit ({exc})") from None
    if not isinstance(d, dict) or d.get("format") != FORMAT_TAG or set(d.get("model1") or {}) != set(KEYS):
        raise ValueError(f"{path}: not a pole-at-start fit (format: {FORMAT_TAG}, model1 keys {', '.join(KEYS)})")
    doc = load_params(d["params"]).to_dict()
    doc.pop("provenance", None)
    doc.pop("intervals", None)
    return block_params(doc, d["model1"]), float(d["model1"]["delta"])
