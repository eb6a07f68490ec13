"""Fabric-friction continuum model for transient granular shear (no YADE needed)."""
from .laws import (
    alpha_model1,
    alpha_model2,
    fabric_angle_deg,
    fabric_norm,
    friction_eq2,
    friction_quadratic,
    steady_state_constant,
)
from .params import ModelParams, load_params, params_from_dict, save_params

__all__ = [
    "ModelParams", "load_params", "params_from_dict", "save_params",
    "alpha_model1", "alpha_model2", "friction_eq2", "friction_quadratic",
    "steady_state_constant", "fabric_norm", "fabric_angle_deg",
]
