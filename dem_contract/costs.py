r"""What a DEM case cost, stage by stage, from its JSON sidecars (docs/data-contract.md).

Every stage ``<stage>.json`` that ``yade_scripts`` writes records the stage's
CPU time of the one-thread YADE process (``cpu_time_s``, immune to other jobs
on the machine), its wall time (``wall_time_s``), its time steps (``steps``)
and the number of disks (``N``). ``stage_costs`` is the one reader of them:
the packing's share, the campaign summary, the DEM studies' cost tables and
the claims' core-hours all read the costs through it.
"""
from __future__ import annotations

import math
from pathlib import Path

from .series import DEMInputError, read_sidecar

#: Sidecar key -> the name of one stage's column (``{stage}`` filled in) and its type.
COST_KEYS = {"cpu_time_s": ("cpu_time_{stage}_s", float),
             "wall_time_s": ("wall_time_{stage}_s", float),
             "steps": ("steps_{stage}", int)}
#: The rules for a missing sidecar or key.
MISSING = ("raise", "nan")


def stage_costs(case_dir, stages, keys=tuple(COST_KEYS), missing: str = "raise") -> dict:
    r"""The per-stage costs of one DEM case, their sums over the stages, and its number of disks.

    For each cost key :math:`k` (CPU seconds, wall seconds, time steps) and
    each stage :math:`j` of ``stages``, the value :math:`c_{k,j}` of the
    stage's sidecar ``<case_dir>/<stage>.json``, and the case's total

    .. math:: C_k = \sum_{j \in \text{stages}} c_{k,j}

    (NaN if any :math:`c_{k,j}` is NaN).

    Parameters
    ----------
    case_dir : str or Path
        The case's folder (``results/dem/<case>/``).
    stages : sequence of str
        The stages to read, in the order of the sums (e.g. ``("pack", "preshear", "heaviside")``).
    keys : sequence of str
        The cost keys read, among ``COST_KEYS``: ``cpu_time_s``, ``wall_time_s``, ``steps``.
    missing : {"raise", "nan"}
        What a missing sidecar or a sidecar without a key (or ``N``) gives:
        ``"raise"`` a ``DEMInputError`` naming the file and the key(s),
        ``"nan"`` NaN for that stage's values (older sidecars, model-made cases).

    Returns
    -------
    dict
        ``N`` (int, the sidecars' common number of disks; NaN if none records
        it), then per stage ``cpu_time_<stage>_s``, ``wall_time_<stage>_s``,
        ``steps_<stage>`` (of the ``keys`` asked, float, float, int), then the
        sums ``cpu_time_s``, ``wall_time_s``, ``steps``.

    Raises
    ------
    DEMInputError
        With ``missing="raise"``: a sidecar is missing or lacks a key. Always:
        a sidecar is not a JSON object, or two stages disagree on ``N``.
    ValueError
        ``missing`` or a key is not one of those allowed (a programming error).
    """
    if missing not in MISSING:
        raise ValueError(f"missing={missing!r}: expected one of {MISSING}")
    unknown = [k for k in keys if k not in COST_KEYS]
    if unknown:
        raise ValueError(f"keys {unknown}: expected among {list(COST_KEYS)}")
    case_dir = Path(case_dir)
    values, disks = {}, {}
    for stage in stages:
        path = case_dir / f"{stage}.json"
        side = read_sidecar(path)
        if missing == "raise":
            if not side:
                raise DEMInputError(f"{path}: file not found (the {stage} stage's sidecar, read for its costs)")
            lacking = [k for k in ("N", *keys) if k not in side]
            if lacking:
                raise DEMInputError(f"{path}: sidecar without {', '.join(lacking)} (read for the stage's costs)")
        if "N" in side:
            disks[stage] = int(side["N"])
        for key in keys:
            name, kind = COST_KEYS[key]
            values[name.format(stage=stage)] = kind(side[key]) if key in side else math.nan
    if len(set(disks.values())) > 1:
        raise DEMInputError(f"{case_dir}: the stages' sidecars disagree on N ({disks})")
    out = {"N": next(iter(disks.values()), math.nan), **values}
    for key in keys:
        out[key] = sum(values[COST_KEYS[key][0].format(stage=stage)] for stage in stages)
    return out
