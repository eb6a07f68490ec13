"""Case labels: the one place that writes and reads the name of a DEM case.

A DEM case is one (pressure, inertial number, seed) of the campaign; its folder
under ``results/dem/`` is named by its label ``p<pressure>_I<inertial number>_s<seed>``,
for instance ``p100000_I0.002_s1``. Numbers are written with 6 significant
digits and no ``+`` in exponents. The seeds of one (pressure, inertial number)
form an ensemble, named by the label without its ``_s<seed>`` part.
"""
from __future__ import annotations

import re

#: A number as it stands in a label (``format_number``'s text): no ``_`` and no ``/``.
NUMBER = r"[^_/]+"


def label_pattern(named_groups: bool = False) -> str:
    """A case label as a regular expression without anchors: the one writing of its form.

    With ``named_groups`` the ensemble (``group``, ``p.._I..``), ``pressure``, ``inertial_number``
    and ``seed`` are groups (``LABEL_RE``); without, it has no group at all, as a Snakemake wildcard
    constraint must (``WILDCARD_CONSTRAINT``: every named group of a rule's pattern is a wildcard).
    """
    def part(name: str, body: str) -> str:
        return f"(?P<{name}>{body})" if named_groups else body

    return part("group", f"p{part('pressure', NUMBER)}_I{part('inertial_number', NUMBER)}") + f"_s{part('seed', '[0-9]+')}"


#: A case label, with the ensemble (``p.._I..``) and the seed as groups.
LABEL_RE = re.compile(f"^{label_pattern(named_groups=True)}$")
#: The constraint of the ``{case}`` wildcard of the DEM rules (workflow/rules/dem.smk).
WILDCARD_CONSTRAINT = label_pattern()


def format_number(x: float) -> str:
    """A number as it appears in a label: 6 significant digits, no '+' in the exponent."""
    return f"{x:.6g}".replace("+", "")


def case_label(pressure: float, inertial_number: float, seed: int) -> str:
    """The label of the case (pressure in Pa, inertial number, seed)."""
    return f"p{format_number(pressure)}_I{format_number(inertial_number)}_s{int(seed)}"


def parse_case_label(label: str) -> dict | None:
    """The parts of a case label, or None when ``label`` is not one.

    Returns
    -------
    dict with ``group`` (the ensemble ``p.._I..``), ``pressure`` and
    ``inertial_number`` (floats) and ``seed`` (int).
    """
    m = LABEL_RE.match(label)
    if m is None:
        return None
    try:
        pressure, inertial_number = float(m["pressure"]), float(m["inertial_number"])
    except ValueError:
        return None
    return dict(group=m["group"], pressure=pressure, inertial_number=inertial_number, seed=int(m["seed"]))


def split_case_label(label: str) -> tuple[str, str]:
    """The ensemble and the seed of a case label, ``p1e5_I0.001_s3`` -> (``p1e5_I0.001``, ``3``).

    A name that is not a case label (``parse_case_label`` returns None) is an
    ensemble of its own: (``label``, ``label``).
    """
    parts = parse_case_label(label)
    return (label, label) if parts is None else (parts["group"], str(parts["seed"]))
