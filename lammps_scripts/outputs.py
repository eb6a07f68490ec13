"""A completed LAMMPS stage's outputs: the final state (a LAMMPS restart file), the CSV and the
sidecar, renamed into `<case_dir>` at once (workfiles.publish), then the work files (checkpoints,
resume.json, the grid file, LAMMPS's log) removed. A mixin of stages.Stage.

The sidecar has every key of yade_scripts' (docs/data-contract.md): `engines` lists the LAMMPS
pair style and fixes, `lammps_version` stands for `yade_version`; `engine` is "lammps", and
`engine_state` carries what the next stage starts from (layout, time origin, strain, dt).
"""
import math
import os
import shutil

import contact
import measure
import protocol
import workfiles
from rows import overlap_stats
from shearing import STATE_SUFFIX


class Outputs:
    def finish(self):
        st = self.st
        workfiles.sync(self.csv)
        self.csv.close()
        self.account_time()
        final_tmp = os.path.join(self.partial, "final.lammps")
        self.lmp.command(f"write_restart {final_tmp}")
        side = self.sidecar()
        workfiles.publish(self.case_dir, self.stage, final_tmp, STATE_SUFFIX, self.csv_path, side)
        self.close()
        shutil.rmtree(self.partial, ignore_errors=True)
        print(f"[{self.stage}] done: {st['rows']} samples, {side['steps']} steps, "
              f"{side['wall_time_s']:.1f} s, {side['particle_steps_per_s']:.3g} particle-steps/s", flush=True)

    def engines(self):
        """The LAMMPS settings that act every step: the pair style and the fixes, in order."""
        return [self.pair_style, *self.fix_lines, *([self.drag] if self.drag else [])]

    def sidecar(self):
        st, der, sc = self.st, self.der, self.scene
        d, p, T0 = der["d"], der["p"], der["T0"]
        snap = self.snap
        w = measure.walls(snap)
        steps = self.step() - st["iter0"]
        n_p = max(1, st["n_acc"])
        p_mean = st["sum_p"] / n_p if st["n_acc"] else math.nan
        law = contact.gran_hooke_history(sc, der)
        sm, sM = sc["material"]["size_ratio_min"], sc["material"]["size_ratio_max"]
        out = dict(
            stage=self.stage, engine="lammps", scene=sc, scene_sha256=self.hash, seed=sc["seed"], N=self.lay["N"],
            N_wall=self.lay["n_wall"], dt=st["dt"], dt_over_tc=st["dt"] / der["tc"], kn=der["kn"], kt=der["kt"],
            kappa=sc["material"]["kappa"], inertial_number=sc["loading"]["inertial_number"],
            U=der["U"], gammadot_nominal=der["gammadot"], time_unit_s=T0,
            steps=steps, samples=st["rows"], engines=self.engines(),
            lammps_version=self.lammps_version, wall_time_s=st["wall_time"],
            particle_steps_per_s=self.lay["N"] * steps / st["wall_time"] if st["wall_time"] > 0 else math.nan,
            cpu_time_s=st["cpu_time"], sampler_cpu_s=st.get("sampler_cpu", 0.0),
            sampling_cost=st.get("sampler_cpu", 0.0) / max(1e-12, st["cpu_time"] - st.get("sampler_cpu", 0.0)),
            resumed=st["resumed"], t_end=(self.time() - st["t_origin"]) / T0, strain_end=st["strain"],
            gap_end=(w["y_top"] - w["y_bot"]) / d,
            sampling_steps=dict(fine=st["fine_every"], coarse=st["coarse_every"], every=st["every"]),
            columns=self.columns(),
            overlap_end_d=overlap_stats(snap.grain_overlaps_d(d)),
            contact_law=dict(gamma_n=law["gamma_n"], gamma_t=law["gamma_t"], restitution_smallest_pair=
                             contact.pair_restitution(sc, der, sm * d, sm * d),
                             restitution_largest_pair=contact.pair_restitution(sc, der, sM * d, sM * d)),
            engine_state=dict(layout=self.lay, t_origin=st["t_origin"], strain=st["strain"], dt=st["dt"],
                              step=self.step()))
        if self.stage == "pack":
            excl = sc["sampling"]["bulk_exclusion_d"] * d
            b = measure.bulk(snap, w["y_bot"] + excl, w["y_top"] - excl, d)
            pw = (w["fy_top"] - w["fy_bot"]) / (2 * der["W"] * d) / p
            out.update(phi=b["phi"], gap=out["gap_end"], converged_at_t=st.get("converged_at_t"),
                       phase_steps=st.get("phase_steps", {}), p_wall_end=pw, kappa_achieved=der["kn"] / (pw * p * d))
        else:
            out.update(strain_start=st["strain_start"], t_start=st["t_start"], p_wall_mean=p_mean,
                       kappa_achieved=der["kn"] / (p_mean * p * d),
                       inertial_number_achieved=(st["sum_gd"] / n_p) / math.sqrt(p_mean),
                       gap_mean=st["sum_gap"] / n_p)
            out.update(protocol.sidecar_keys(self.stage, st))
        return out
