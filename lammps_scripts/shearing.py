"""The pre-shear and the Heaviside reversal in LAMMPS: the previous stage's final state and the
walls' speeds. A mixin of stages.Stage (yade_scripts/shearing.py's start, for these two stages).
"""
import json
import math
import os

import cell
from stageerrors import InputError

PREVIOUS = {"preshear": "pack", "heaviside": "preshear"}
STATE_SUFFIX = ".final.lammps"  # a stage's final state: a LAMMPS restart file


class Shearing:
    def start_from_previous(self, st, steps_per_strain):
        """Load the previous stage's final state (its restart file, and its sidecar's
        engine_state: the layout, the time origin and the strain) and set the walls' speeds:
        +U at the top and -U at the bottom for the pre-shear, reversed at once for heaviside."""
        der, sc, smp = self.der, self.scene, self.scene["sampling"]
        before = PREVIOUS[self.stage]
        prev = os.path.join(self.case_dir, before + STATE_SUFFIX)
        side_path = os.path.join(self.case_dir, f"{before}.json")
        if not os.path.exists(prev) or not os.path.exists(side_path):
            raise InputError(f"missing input {prev} or {side_path}: run stage {before} first")
        with open(side_path) as f:
            side = json.load(f)
        pst = side.get("engine_state")
        if side.get("engine") != "lammps" or pst is None:
            raise InputError(f"{side_path} was not written by lammps_scripts (engine = {side.get('engine')!r})")
        if side.get("scene_sha256") != self.hash:
            print(f"[{self.stage}] warning: {prev} was made from another scene file", flush=True)
        cell.load_state(self.lmp, prev)
        self.lay = pst["layout"]
        st.update(dt=pst["dt"], t_origin=pst["t_origin"], strain=pst["strain"], iter0=self.step(),
                  load=der["p"] * der["W"] * der["d"], friction=sc["material"]["friction"], damping=0.0)
        if self.stage == "preshear":
            st["t_origin"] = self.time()
            st["strain"] = 0.0
        st["strain_start"], st["t_start"] = st["strain"], (self.time() - st["t_origin"]) / der["T0"]
        st["n_transition"] = 0
        strain = sc[self.stage]["strain"]
        st["n_steps"] = int(math.ceil(strain * steps_per_strain))
        st["fine_end"] = st["iter0"] + int(math.ceil(smp["fine_window"] * steps_per_strain))
        st["direction"] = 1 if self.stage == "preshear" else -1
        st["every"] = st["fine_every"]

    def apply_wall_speeds(self):
        """Walls at direction x U (top) and -direction x U (bottom); at rest in the pack."""
        u = 0.0 if self.stage == "pack" else self.st["direction"] * self.der["U"]
        cell.set_wall_speeds(self.lmp, u, -u)
