"""The pack stage's phases: compression, ramp, settling (docs/scene.md, Packing).

A mixin of stages.Stage: the methods act on the stage's state `self.st` (saved in
O.tags with every checkpoint) and on the simulation `O`.
"""
import math

import build
import engines
import packphases
from stageerrors import InputError
from yade.wrapper import Omega

O = Omega()


class Packing:
    def _start_pack(self, st):
        """A new cell (build.new_cell) and the pack's state: compaction first, at pack.friction."""
        der, sc = self.der, self.scene
        try:
            self.lay = build.new_cell(sc, der)
        except build.PlacementError as e:
            raise InputError(str(e))
        st.update(dt=der["dt"], t_origin=0.0, strain=0.0, iter0=0, time0=0.0, phase="compress",
                  load=sc["pack"]["compaction_pressure"] * der["p"] * der["W"] * der["d"],
                  phase_steps={})
        # compaction with a lower friction (restored before the settling, see _enter)
        build.set_friction(packphases.friction(sc, "compress"))
        # pack.damping acts on the grains only: a damped wall falls at half its load
        build.set_wall_damped(self.lay, False)
        st["every"] = max(1, int(round(sc["pack"]["check_interval"] * der["T0"] / der["dt"])))
        st["n_steps"] = int(math.ceil(sc["pack"]["max_time"] * der["T0"] / der["dt"]))
        st["fine_end"] = 0

    def _ke_mean(self):
        """Mean squared grain velocity (translation only: a free rattler may spin for ever), in p/rho:
        sum_i |v_i|^2 / (N V0^2) over the grains (ids 0..N-1)."""
        b = O.bodies
        v2 = sum(b[i].state.vel.squaredNorm() for i in range(self.lay["N"]))
        return v2 / self.lay["N"] / self.der["V0"] ** 2

    def _enter(self, phase):
        """What entering pack phase ``phase`` (packphases.check) does in YADE: the grains' damping
        (packphases.damping); the settling: the grains' friction back to material.friction (on a
        packing held at p this only widens the Coulomb cones, the settling then checks that it stays
        still) and, with pack.quench, the grains at rest; done: the top wall damped as every body in
        the saved packing, the run paused."""
        engines.set_damping(packphases.damping(self.scene, phase))
        if phase == "settle":
            build.set_friction(packphases.friction(self.scene, phase))
            if self.scene["pack"]["quench"]:
                build.quench_grains(self.lay)
        if phase == "done":  # the packing is saved with the scene's own damping, on every body
            build.set_wall_damped(self.lay, True)
            self.done = True
            O.pause()

    def _pack_control(self, ke, wall_speed, pw):
        """One check of the pack's phases (packphases.check), the phases entered acted on, the
        ramp's load set."""
        st = self.st
        load = st["load"]
        for phase in packphases.check(st, self.scene, self.der, self._t, self._it - st["iter0"], ke, wall_speed, pw):
            self._enter(phase)
        if st["load"] != load:
            build.set_wall_load(self.lay, st["load"])
