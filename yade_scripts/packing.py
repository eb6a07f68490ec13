"""The pack stage's phases: compression, ramp, settling (docs/scene.md, Packing).

A mixin of stages.Stage: the methods act on the stage's state `self.st` (saved in
O.tags with every checkpoint) and on the simulation `O`.
"""
import math

import build
import engines
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
        # compaction with a lower friction (restored before the settling, see _pack_control)
        build.set_friction(self._pack_friction())
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

    def _pack_friction(self):
        """The grains' friction coefficient during the compression and the ramp: pack.friction,
        or material.friction if it is null."""
        mu = self.scene["pack"]["friction"]
        return self.scene["material"]["friction"] if mu is None else mu

    def _pack_damping(self):
        """Cundall damping of the grains in the current pack phase: pack.damping in the ramp and the
        settling; effects.damping in the compression (damped grains resist the falling wall and slow
        the creep of the packing under the compaction load: measured, docs/scene.md) and once done
        (the saved packing). The top wall is not damped until done (build.set_wall_damped)."""
        return self.scene["pack"]["damping"] if self.st["phase"] in ("ramp", "settle") else self.scene["effects"]["damping"]

    def _enter(self, phase):
        """Start pack phase ``phase`` (compress, ramp, settle, done) with its damping; the steps of the
        phase that ends go to st['phase_steps']."""
        st = self.st
        ps = st.setdefault("phase_steps", {})
        ps[st["phase"]] = self._it - st["iter0"] - sum(ps.values())
        st["phase"] = phase
        engines.set_damping(self._pack_damping())
        if phase == "done":  # the packing is saved with the scene's own damping, on every body
            build.set_wall_damped(self.lay, True)

    def _pack_control(self, ke, wall_speed, pw):
        """The pack's phases: compress -> ramp -> settle (docs/scene.md, Packing).

        compress: the top wall (a periodic cell's height) moves under the compaction load with the
        grains' friction at pack.friction, until jammed;
        ramp: the load goes linearly to p in pack.ramp_time, grains damped by pack.damping;
        settle: friction back to material.friction, grains at rest (pack.quench), then done after
        two checks in a row with ke < ke_max, wall speed < wall_speed_max and |p_wall - p| small.
        """
        st, pk, der = self.st, self.scene["pack"], self.der
        full = der["p"] * der["W"] * der["d"]
        settled = ke < pk["ke_max"] and wall_speed < pk["wall_speed_max"]
        if st["phase"] == "compress":
            # the wall has stopped on a jammed packing (a looser kinetic criterion: the
            # low compaction load makes the last rattlers slow to calm down)
            if wall_speed < pk["wall_speed_max"] and ke < 100 * pk["ke_max"]:
                self._enter("ramp")
                st["ramp_start"] = self._t
                print(f"[pack] jammed at the compaction load, t = {self._t / der['T0']:.1f}: ramping to p", flush=True)
        if st["phase"] == "ramp":
            f0 = pk["compaction_pressure"] * full
            ramp = pk["ramp_time"] * der["T0"]
            x = min(1.0, (self._t - st["ramp_start"]) / ramp) if ramp > 0 else 1.0
            st["load"] = f0 + (full - f0) * x
            build.set_wall_load(self.lay, st["load"])
            if x >= 1.0:
                self._enter("settle")
                st["pack_ok"] = 0
                # back to the grains' friction before the settling: on a packing held at p this
                # only widens the Coulomb cones, the settling then checks that it stays still
                build.set_friction(self.scene["material"]["friction"])
                if pk["quench"]:
                    build.quench_grains(self.lay)
        elif st["phase"] == "settle":
            ok = settled and abs(pw - 1) < pk["pressure_tolerance"]
            st["pack_ok"] = st["pack_ok"] + 1 if ok else 0
            if st["pack_ok"] >= 2:
                st["converged_at_t"] = self._t / der["T0"]
                self._enter("done")
                self.done = True
                O.pause()
