"""The pack stage's phases in LAMMPS: compression, ramp, settling (docs/scene.md, Packing).

A mixin of stages.Stage, the same phases and criteria as yade_scripts/packing.py; the grains'
Cundall damping of the ramp and the settling is a viscous drag here (cell.set_grain_damping).
"""
import math

import cell
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
        st["friction"] = self.pack_friction()
        st["damping"] = 0.0
        st["every"] = max(1, int(round(sc["pack"]["check_interval"] * der["T0"] / der["dt"])))
        st["n_steps"] = int(math.ceil(sc["pack"]["max_time"] * der["T0"] / der["dt"]))
        st["fine_end"] = 0

    def pack_friction(self):
        """pack.friction, or material.friction if it is null."""
        mu = self.scene["pack"]["friction"]
        return self.scene["material"]["friction"] if mu is None else mu

    def ke_mean(self, snap):
        """Mean squared grain velocity (translation) in p/rho."""
        v = snap.v[: self.lay["N"]]
        return float((v**2).sum()) / self.lay["N"] / self.der["V0"] ** 2

    def enter(self, phase):
        """Start pack phase ``phase``; the steps of the phase that ends go to st['phase_steps'].
        The grains are damped (pack.damping) in the ramp and the settling only."""
        st = self.st
        ps = st["phase_steps"]
        ps[st["phase"]] = self.step() - st["iter0"] - sum(ps.values())
        st["phase"] = phase
        damped = phase in ("ramp", "settle")
        st["damping"] = self.scene["pack"]["damping"] if damped else 0.0
        self.apply_damping()

    def apply_damping(self):
        """The grains' drag of the current phase: gamma = damping sqrt(kn m_d) (cell.set_grain_damping)."""
        gamma = self.st["damping"] * math.sqrt(self.der["kn"] * self.der["m_d"])
        self.drag = cell.set_grain_damping(self.lmp, gamma)
        self.setup_needed = True

    def pack_control(self, ke, wall_speed, pw):
        """compress -> ramp -> settle -> done, as yade_scripts/packing.Packing._pack_control."""
        st, pk, der = self.st, self.scene["pack"], self.der
        full = der["p"] * der["W"] * der["d"]
        settled = ke < pk["ke_max"] and wall_speed < pk["wall_speed_max"]
        t = self.time()
        if st["phase"] == "compress" and wall_speed < pk["wall_speed_max"] and ke < 100 * pk["ke_max"]:
            self.enter("ramp")
            st["ramp_start"] = t
            print(f"[pack] jammed at the compaction load, t = {t / der['T0']:.1f}: ramping to p", flush=True)
        if st["phase"] == "ramp":
            f0 = pk["compaction_pressure"] * full
            ramp = pk["ramp_time"] * der["T0"]
            x = min(1.0, (t - st["ramp_start"]) / ramp) if ramp > 0 else 1.0
            st["load"] = f0 + (full - f0) * x
            cell.set_wall_load(self.lmp, st["load"], self.lay["n_wall"])
            if x >= 1.0:
                self.enter("settle")
                st["pack_ok"] = 0
                st["friction"] = self.scene["material"]["friction"]
                cell.set_friction(self.lmp, self.scene, der, st["friction"])
                self.setup_needed = True  # a new pair style's settings: LAMMPS's setup before the next run
                if pk["quench"]:
                    cell.quench_grains(self.lmp)
        elif st["phase"] == "settle":
            ok = settled and abs(pw - 1) < pk["pressure_tolerance"]
            st["pack_ok"] = st["pack_ok"] + 1 if ok else 0
            if st["pack_ok"] >= 2:
                st["converged_at_t"] = t / der["T0"]
                self.enter("done")
                self.done = True
