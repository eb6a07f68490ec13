r"""Synthetic DEM cases for the calibration tests: ``dem_contract.synthetic`` with the calibration's defaults.

The calibration is tested on time series that ``model.simulate`` generates from
known parameters, in exactly the DEM layout (``dem_contract.synthetic`` writes
them; its docstring states the conventions). The defaults here make them what
a calibration sees: Gaussian noise of the magnitude measured on one
500-disk run (0.04 in mu, 0.0125 in each fabric component per sample; docs/data-contract.md), a
pre-shear of 3 strain from an isotropic fabric (so the transient to steady
state is in the data and the steady-state check has something to judge), and
reversal runs of 0.4 strain. Nothing here is a stand-in for the DEM: it is the
known truth the round-trip tests compare with.
"""
from __future__ import annotations

from dem_contract import synthetic
from dem_contract.synthetic import FABRIC_NOISE, MU_NOISE

#: ``dem_contract.synthetic.write_case`` options that the calibration's test cases change.
DEFAULTS = dict(preshear_strain=3.0, reversal_strain=0.4, fabric_noise=FABRIC_NOISE, mu_noise=MU_NOISE,
                A_start=(0.0, 0.0))


def write_case(case_dir, params, seed, **kw):
    """Write one synthetic case directory (``DEFAULTS``, overridden by ``kw``); return its path."""
    return synthetic.write_case(case_dir, params, seed=seed, **{**DEFAULTS, **kw})


def write_ensemble(root, params, seeds=(1, 2, 3, 4), group="p1_I0.001", **kw):
    """Write one case per seed, named ``<group>_s<seed>``; return their paths."""
    return synthetic.write_ensemble(root, params, seeds=seeds, group=group, **{**DEFAULTS, **kw})
