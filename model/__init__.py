"""Fabric-friction continuum model for transient granular shear (no YADE needed).

Quick start::

    from model import default_params, heaviside, simulate
    table = simulate(default_params(), heaviside(1.0, 2.0))

See ``model/README.md`` for the command line and the choice of integrator.
"""
from .histories import (
    History,
    concatenate,
    heaviside,
    pure_shear,
    rest,
    rigid_rotation,
    sinusoidal,
    steady_shear,
    superpose_rotation,
    tabulated,
    velocity_gradient,
)
from .integrate import (
    COLUMNS,
    DEFAULT_ATOL,
    DEFAULT_METHOD,
    DEFAULT_RTOL,
    METHODS,
    simulate,
    steady_state,
)
from .laws import (
    alpha_model1,
    alpha_model2,
    fabric_angle_deg,
    fabric_norm,
    friction_eq2,
    friction_quadratic,
    steady_state_constant,
)
from .params import DEFAULT_PARAMS_YAML, ModelParams, default_params, load_params, params_from_dict, save_params
from .rhs import FabricDivergence, PoleError

__all__ = [
    "ModelParams", "load_params", "params_from_dict", "save_params", "default_params", "DEFAULT_PARAMS_YAML",
    "alpha_model1", "alpha_model2", "friction_eq2", "friction_quadratic",
    "steady_state_constant", "fabric_norm", "fabric_angle_deg",
    "simulate", "steady_state", "PoleError", "FabricDivergence", "COLUMNS", "METHODS",
    "DEFAULT_METHOD", "DEFAULT_RTOL", "DEFAULT_ATOL",
    "History", "heaviside", "sinusoidal", "tabulated", "rest", "steady_shear", "pure_shear",
    "rigid_rotation", "velocity_gradient", "concatenate", "superpose_rotation",
]
