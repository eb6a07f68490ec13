"""A completed stage's outputs: the final state, the CSV and the sidecar, renamed into
`<case_dir>` at once, then the work files removed. A mixin of stages.Stage.
"""
import json
import os
import re
import time

import yade
from yade.wrapper import Omega

import measure
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
        """The sidecar (workfiles.StageFiles.common_sidecar) with YADE's version."""
        d = self.der["d"]
        w = measure.walls(self.lay)
        phi = None
        if self.stage == "pack":
            excl = self.scene["sampling"]["bulk_exclusion_d"] * d
            phi = self.bulk.measure(self.lay, w["y_bot"] + excl, w["y_top"] - excl, self.der["W"])["phi"]
        out = self.common_sidecar("yade", self.engine_names, O.iter - self.st["iter0"], O.time, w,
                                  measure.grain_overlaps_d(self.lay["N"], d), phi)
        out["yade_version"] = yade.config.version
        return out
