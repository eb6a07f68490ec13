"""External DEM data through ``python -m dem_contract import`` (docs/own-dem-data.md), on model-made runs.

The runs are written by the model itself (``dem_contract.synthetic``, the
calibration's defaults: the DEM's noise, a pre-shear from isotropy) and then
put into the minimal format a user brings: one CSV per run holding the whole
history, with only the required columns, a start from rest (the wall speed
steps from 0 at t = 0), and a metadata YAML.
"""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from calibrate import synthetic
from dem_contract import DEMInputError, read_series
from dem_contract.importer import MINIMAL_COLUMNS, import_cases
from model import default_params

ROOT = Path(__file__).resolve().parents[1]
PRESHEAR = 2.0


def run_cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", *args], cwd=cwd or ROOT, capture_output=True, text=True)


def minimal_runs(made: Path, out: Path, seed: int, protocols, mirror=False, extra=()):
    """The model-made case ``made`` as the minimal CSVs a user brings: one per run, pre-shear included, from rest."""
    pre = pd.read_csv(made / "preshear.csv")
    files = {}
    for protocol in protocols:
        run = pd.read_csv(made / f"{protocol}.csv").iloc[1:]      # its first row is the pre-shear's last
        whole = pd.concat([pre, run], ignore_index=True)[list(MINIMAL_COLUMNS) + list(extra)]
        whole.loc[0, "gammadot"] = 0.0                           # at rest at t = 0
        if mirror:                                               # a simulator shearing towards -x
            for c in ("strain", "gammadot", "A_xy", "sigma_xy"):
                whole[c] = -whole[c]
        name = f"seed{seed}_{protocol}.csv"
        whole.to_csv(out / name, index=False)
        files[protocol] = name
    return files


def write_external(tmp: Path, seeds=(1, 2, 3), protocols=("heaviside", "sinusoidal"), cell=None, mirror=False,
                   extra=(), costs=None, I=1e-3):
    """Model-made runs in the minimal format plus their metadata YAML under ``tmp``; returns the YAML's path."""
    made, ext = tmp / "made", tmp / "external"
    ext.mkdir(parents=True, exist_ok=True)
    cases = []
    for s in seeds:
        case = synthetic.write_case(made / f"s{s}", default_params(), seed=s, preshear_strain=PRESHEAR,
                                    I=I, protocols=protocols)
        files = minimal_runs(case, ext, s, protocols, mirror, extra)
        sign = -1 if mirror else 1
        runs = [{"file": files[p], "protocol": p,
                 "reversals": [{"strain": sign * PRESHEAR} | ({"transition_strain": 0.1} if p == "sinusoidal" else {})]}
                for p in protocols]
        cases.append({"seed": s, "runs": runs} | ({"costs": costs} if costs else {}))
    meta = {"pressure": 1.0e5, "inertial_number": I, "simulator": "model-made test data", "cases": cases}
    if cell:
        meta["cell"] = cell
    (ext / "case.yaml").write_text(yaml.safe_dump(meta, sort_keys=False))
    return ext / "case.yaml"


# --------------------------------------------------------------------------- the reader: a start from rest


def test_reader_accepts_a_start_from_rest_and_still_refuses_a_strain_jump(tmp_path):
    t = np.arange(0.0, 10.0, 1.0)
    g = np.where(t == 0.0, 0.0, 1e-3)                 # the walls start at t = 0 from rest
    strain = np.concatenate([[0.0], 1e-3 * t[1:]])    # the rate stepped at once: the first step is 1e-3 dt
    d = pd.DataFrame({"t": t, "strain": strain, "gammadot": g})
    d.to_csv(tmp_path / "rest.csv", index=False)
    assert len(read_series(tmp_path / "rest.csv", ("t", "strain", "gammadot"))) == 10
    d.loc[5:, "strain"] += 0.3                          # a jump later in the run is still refused
    d.to_csv(tmp_path / "jump.csv", index=False)
    with pytest.raises(DEMInputError, match=r"jump\.csv: strain jumps by \+0\.301 between data rows 5 and 6"):
        read_series(tmp_path / "jump.csv", ("t", "strain", "gammadot"))
