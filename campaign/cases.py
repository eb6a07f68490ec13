"""The DEM cases of a campaign: one per (pressure, inertial number, seed).

The rate is given in the config either as inertial numbers or as wall speeds U
(top wall at +U, bottom at -U); a wall speed converts to the inertial number with
the nominal gap H = H_over_d d:

    gammadot = 2 U / H,    I = gammadot d / sqrt(p / rho).
"""
from __future__ import annotations

from itertools import product

from dem_contract.labels import case_label


def inertial_number_of_wall_velocity(U: float, pressure: float, material: dict, cell: dict) -> float:
    """I = (2 U / H) d / sqrt(p / rho), with H = H_over_d d (the nominal gap)."""
    d, rho = material["diameter"], material["density"]
    H = cell["H_over_d"] * d
    return 2 * U / H * d / (pressure / rho) ** 0.5


def rates(config: dict, pressure: float) -> list[float]:
    """The inertial numbers run at ``pressure``: ``loading.inertial_numbers``, or the wall speeds converted."""
    loading = config["loading"]
    if "inertial_numbers" in loading:
        return [float(I) for I in loading["inertial_numbers"]]
    return [inertial_number_of_wall_velocity(U, pressure, config["material"], config["cell"])
            for U in loading["wall_velocities"]]


def cases(config: dict) -> dict[str, dict]:
    """The DEM cases of the campaign, in config order.

    Returns
    -------
    dict
        case label (``dem_contract.labels.case_label``) -> dict(pressure, inertial_number, seed).
        Two values that round to the same label make one case: ``preflight`` rejects that.
    """
    table = {}
    for p in config["loading"]["pressures"]:
        for I, seed in product(rates(config, p), config["seeds"]):
            table[case_label(p, I, seed)] = dict(pressure=float(p), inertial_number=float(I), seed=int(seed))
    return table
