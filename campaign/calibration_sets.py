"""Calibration sets: which DEM cases and protocols each calibration learns from.

The held-out comparisons use the other cases and protocols.
"""
from __future__ import annotations

import math

from dem_contract.labels import format_number


def same_value(a: float, b: float) -> bool:
    """Two pressures or inertial numbers name the same loading (relative difference below 1e-6)."""
    return math.isclose(float(a), float(b), rel_tol=1e-6, abs_tol=0.0)


def default_sets(cases: dict) -> dict:
    """The sets that always exist: "all", and with several loadings one set per pressure and per I.

    With several pressures (or inertial numbers) the held-out comparison
    calibrates on one and predicts the others.
    """
    sets = {"all": {}}
    pressures = sorted({case["pressure"] for case in cases.values()})
    rates = sorted({case["inertial_number"] for case in cases.values()})
    if len(pressures) > 1:
        sets.update({f"p{format_number(p)}": {"pressures": [p]} for p in pressures})
    if len(rates) > 1:
        sets.update({f"I{format_number(I)}": {"inertial_numbers": [I]} for I in rates})
    return sets


def calibration_sets(config: dict, cases: dict) -> dict:
    """Calibration sets: name -> dict(cases=[labels], protocols=[...]).

    The default sets (``default_sets``) and those of ``calibration.sets``; a set
    may restrict protocols and pick pressures / inertial numbers / seeds ("all" or a
    missing key keeps every value of the campaign). A set that selects no case
    or no protocol is left out (``preflight`` rejects such a set before this).
    """
    protocols_all = list(config["protocols"])
    sets = default_sets(cases)
    sets.update((config.get("calibration") or {}).get("sets") or {})
    out = {}
    for name, spec in sets.items():
        protocols = [p for p in spec.get("protocols", protocols_all) if p in protocols_all]
        labels = [label for label, case in cases.items() if selects(spec, case)]
        if labels and protocols:
            out[name] = dict(cases=labels, protocols=protocols)
    return out


def selects(spec: dict, case: dict) -> bool:
    """Whether the set ``spec`` takes ``case`` (its pressure, inertial number and seed are listed, or "all")."""
    wanted_seeds = spec.get("seeds", "all")
    if wanted_seeds != "all" and int(case["seed"]) not in {int(s) for s in wanted_seeds}:
        return False
    for key, value in (("pressures", case["pressure"]), ("inertial_numbers", case["inertial_number"])):
        wanted = spec.get(key, "all")
        if wanted != "all" and not any(same_value(value, w) for w in wanted):
            return False
    return True
