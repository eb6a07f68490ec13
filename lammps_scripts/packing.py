"""The pack stage's phases in LAMMPS: compression, ramp, settling (docs/scene.md, Packing).

A mixin of stages.Stage: the phases and their criteria are yade_scripts/packphases.py's, shared with
YADE's stage; this module does what entering a phase does in LAMMPS. The grains' Cundall damping of
the ramp and the settling is a viscous drag here (cell.set_grain_damping).
"""
import math

import cell
import packphases
import placement
from stageerrors import InputError


class Packing:
    def start_pack(self, st):
        """A new cell (cell.new_cell) and the pack's state: compaction first, at pack.friction."""
        der, sc = self.der, self.scene
        try:
            self.lay = cell.new_cell(self.lmp, sc, der, self.partial)
        except placement.PlacementError as e:
            raise InputError(str(e))
        st.update(dt=der["dt"], t_origin=0.0, strain=0.0, iter0=0, phase="compress", phase_steps={},
                  load=sc["pack"]["compaction_pressure"] * der["p"] * der["W"] * der["d"])
        st["friction"] = packphases.friction(sc, "compress")
        st["damping"] = packphases.damping(sc, "compress")
        st["every"] = max(1, int(round(sc["pack"]["check_interval"] * der["T0"] / der["dt"])))
        st["n_steps"] = int(math.ceil(sc["pack"]["max_time"] * der["T0"] / der["dt"]))
        st["fine_end"] = 0

    def ke_mean(self, snap):
        """Mean squared grain velocity (translation) in p/rho."""
        v = snap.v[: self.lay["N"]]
        return float((v**2).sum()) / self.lay["N"] / self.der["V0"] ** 2

    def enter(self, phase):
        """What entering pack phase ``phase`` (packphases.check) does in LAMMPS: the grains' drag of
        its damping; the settling: the grains' friction back to material.friction (the pair style's
        settings: LAMMPS's setup before the next run) and, with pack.quench, the grains at rest;
        done: the stage ends."""
        st, sc = self.st, self.scene
        st["damping"] = packphases.damping(sc, phase)
        self.apply_damping()
        if phase == "settle":
            st["friction"] = packphases.friction(sc, phase)
            cell.set_friction(self.lmp, sc, self.der, st["friction"])
            self.setup_needed = True
            if sc["pack"]["quench"]:
                cell.quench_grains(self.lmp)
        if phase == "done":
            self.done = True

    def apply_damping(self):
        """The grains' drag of st's damping: gamma = damping sqrt(kn m_d) (cell.set_grain_damping)."""
        gamma = self.st["damping"] * math.sqrt(self.der["kn"] * self.der["m_d"])
        self.drag = cell.set_grain_damping(self.lmp, gamma)
        self.setup_needed = True

    def pack_control(self, ke, wall_speed, pw):
        """One check of the pack's phases (packphases.check), the phases entered acted on, the
        ramp's load set."""
        st = self.st
        load = st["load"]
        for phase in packphases.check(st, self.scene, self.der, self.time(), self.step() - st["iter0"], ke,
                                      wall_speed, pw):
            self.enter(phase)
        if st["load"] != load:
            cell.set_wall_load(self.lmp, st["load"], self.lay["n_wall"])
