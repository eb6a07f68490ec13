"""The pre-shear and every reversal stage in LAMMPS: the previous stage's final state, the walls'
speeds, a reversal stage's segments and the half-cosine turn. A mixin of stages.Stage.

The protocol is yade_scripts/protocol.py's, shared with YADE's stages: the pre-shear from the
packing at +U (top) and -U (bottom); heaviside, sinusoidal and every schedule or train from the
pre-shear, as segments cut between two runs (stages.Stage.run asks `next_boundary`), where
`enter_segment` writes the row just before a reversal and turns the walls at once, or starts a
half cosine that the run loop follows one step at a time (`follow_transition`: the speed after
each step, as YADE's per-step PyRunner sets it).
"""
import json
import math
import os

import cell
import protocol
import scene as scenemod
from stageerrors import InputError

PREVIOUS = {"preshear": "pack"}  # every reversal stage (heaviside, sinusoidal, a schedule) starts from the pre-shear
STATE_SUFFIX = ".final.lammps"  # a stage's final state: a LAMMPS restart file


class Shearing:
    def start_from_previous(self, st, steps_per_strain):
        """Load the previous stage's final state (its restart file, and its sidecar's
        engine_state: the layout, the time origin and the strain); the pre-shear's length and
        speed, or a reversal stage's plan (protocol.plan; its first segment entered in
        `apply_wall_speeds`, once the fixes exist)."""
        der, sc, smp = self.der, self.scene, self.scene["sampling"]
        before = PREVIOUS.get(self.stage, "preshear")
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
        if self.stage == "preshear":
            st["n_steps"] = int(math.ceil(sc["preshear"]["strain"] * steps_per_strain))
            st["fine_end"] = st["iter0"] + int(math.ceil(smp["fine_window"] * steps_per_strain))
            st["direction"] = 1
        else:
            protocol.plan(st, scenemod.segments(sc, self.stage), smp["fine_window"], steps_per_strain, st["iter0"])
        st["every"] = st["fine_every"]

    def apply_wall_speeds(self):
        """The walls' speeds at a fresh start: at rest in the pack, +U/-U in the pre-shear, a
        reversal stage's first segment entered (protocol.enter)."""
        if self.stage == "pack":
            cell.set_wall_speeds(self.lmp, 0.0, 0.0)
        elif self.stage == "preshear":
            cell.set_wall_speeds(self.lmp, self.der["U"], -self.der["U"])
        else:
            self.enter_segment(0, at_start=True)

    def next_boundary(self):
        """Steps since the stage's start at which the next segment begins (None: none)."""
        return protocol.next_boundary(self.st)

    def enter_segment(self, k, at_start=False):
        """Start segment k between two steps: a row for the state just before a reversal (not at
        the stage's start: the row one sampling interval in is its first), the new wall speeds
        or the start of the half cosine towards them, the fine sampling grid from here."""
        st, der = self.st, self.der
        turn = protocol.reverses(st, k)
        if turn and not at_start:
            self.sample()
        u = protocol.enter(st, k, self.step(), (self.time() - st["t_origin"]) / der["T0"], der)
        cell.set_wall_speeds(self.lmp, u, -u)
        if turn:
            st["period"] = st["fine_every"]  # the next row one fine interval after the reversal

    def in_transition(self):
        """True while a half cosine needs the wall speed set after the next step."""
        return protocol.in_transition(self.st, self.step())

    def follow_transition(self):
        """After a step of a half cosine: the walls at its speed for the state now (protocol.transition_speed)."""
        u = protocol.transition_speed(self.st, self.der, self.step())
        cell.set_wall_speeds(self.lmp, u, -u)
