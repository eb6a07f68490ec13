"""A completed stage's outputs: the final state, the CSV and the sidecar, renamed into
`<case_dir>` at once, then the work files removed. A mixin of stages.Stage.
"""
import json
import math
import os
import re
import time

import yade
from yade.wrapper import Omega

import measure
import protocol
import workfiles
from checkpoint import CHECKPOINTS, save_state

O = Omega()


class Outputs:
    def finish(self):
        st = self.st
        workfiles.sync(self.csv)
        self.csv.close()
        st["wall_time"] += time.time() - self.t_wall0
        st["cpu_time"] = st.get("cpu_time", 0.0) + time.process_time() - self.cpu0
        O.tags["ys_state"] = json.dumps(st)
        final_tmp = os.path.join(self.partial, "final.yade.gz")
        save_state(final_tmp)
        side = self.sidecar()
        workfiles.publish(self.case_dir, self.stage, final_tmp, ".final.yade.gz", self.csv_path, side)
        self._remove_work_files()
        print(f"[{self.stage}] done: {st['rows']} samples, {O.iter - st['iter0']} steps, "
              f"{side['wall_time_s']:.1f} s, {side['particle_steps_per_s']:.3g} particle-steps/s", flush=True)

    def _remove_work_files(self):
        """Remove this stage's own work files, then its folder if nothing else is in it.

        Own files: the checkpoints, resume.json and the temporary saves of save_state
        (`tmp<pid>_*.yade.gz`, left behind only by a process killed while saving).
        """
        names = [*CHECKPOINTS, workfiles.RESUME, workfiles.RESUME + ".tmp"]
        names += [n for n in os.listdir(self.partial) if re.fullmatch(r"tmp\d+_.*\.yade\.gz", n)]
        for name in names:
            try:
                os.remove(os.path.join(self.partial, name))
            except FileNotFoundError:
                pass
        try:
            os.rmdir(self.partial)
        except OSError as e:
            print(f"[{self.stage}] {self.partial} left in place: {e}", flush=True)

    def sidecar(self):
        st, der, sc = self.st, self.der, self.scene
        d, p, T0 = der["d"], der["p"], der["T0"]
        w = measure.walls(self.lay)
        steps = O.iter - st["iter0"]
        n_p = max(1, st["n_acc"])
        p_mean = st["sum_p"] / n_p if st["n_acc"] else math.nan
        out = dict(
            stage=self.stage, engine="yade", scene=sc, scene_sha256=self.hash, seed=sc["seed"], N=self.lay["N"],
            N_wall=self.lay["n_wall"], dt=st["dt"], dt_over_tc=st["dt"] / der["tc"], kn=der["kn"], kt=der["kt"],
            kappa=sc["material"]["kappa"], inertial_number=sc["loading"]["inertial_number"],
            U=der["U"], gammadot_nominal=der["gammadot"], time_unit_s=T0,
            steps=steps, samples=st["rows"], engines=self.engine_names,
            yade_version=yade.config.version, wall_time_s=st["wall_time"],
            particle_steps_per_s=self.lay["N"] * steps / st["wall_time"] if st["wall_time"] > 0 else math.nan,
            cpu_time_s=st["cpu_time"], sampler_cpu_s=st.get("sampler_cpu", 0.0),
            sampling_cost=st.get("sampler_cpu", 0.0) / max(1e-12, st["cpu_time"] - st.get("sampler_cpu", 0.0)),
            resumed=st["resumed"], t_end=(O.time - st["t_origin"]) / T0, strain_end=st["strain"],
            gap_end=(w["y_top"] - w["y_bot"]) / d,
            sampling_steps=dict(fine=st["fine_every"], coarse=st["coarse_every"], every=st["every"]),
            columns=self.columns(),
            overlap_end_d=measure.overlap_stats(measure.grain_overlaps_d(self.lay["N"], d)))
        if self.stage == "pack":
            excl = sc["sampling"]["bulk_exclusion_d"] * d
            b = self.bulk.measure(self.lay, w["y_bot"] + excl, w["y_top"] - excl, der["W"])
            pw = (w["fy_top"] - w["fy_bot"]) / (2 * der["W"] * d) / p
            out.update(phi=b["phi"], gap=out["gap_end"], converged_at_t=st.get("converged_at_t"),
                       phase_steps=st.get("phase_steps", {}),
                       p_wall_end=pw, kappa_achieved=der["kn"] / (pw * p * d))
        else:
            out.update(strain_start=st["strain_start"], t_start=st["t_start"], p_wall_mean=p_mean,
                       kappa_achieved=der["kn"] / (p_mean * p * d),
                       inertial_number_achieved=(st["sum_gd"] / n_p) / math.sqrt(p_mean),
                       gap_mean=st.get("sum_gap", math.nan) / n_p)
            out.update(protocol.sidecar_keys(self.stage, st))
        return out
