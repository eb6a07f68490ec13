"""A completed LAMMPS stage's outputs: the final state (a LAMMPS restart file), the CSV and the
sidecar, renamed into `<case_dir>` at once (workfiles.publish), then the work files (checkpoints,
resume.json, the grid file, LAMMPS's log) removed. A mixin of stages.Stage.

The sidecar has every key of yade_scripts' (docs/data-contract.md): `engines` lists the LAMMPS
pair style and fixes, `lammps_version` stands for `yade_version`; `engine` is "lammps", and
`engine_state` carries what the next stage starts from (layout, time origin, strain, dt).
"""
import os
import shutil

import contact
import measure
import workfiles
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
        """The sidecar (workfiles.StageFiles.common_sidecar) with LAMMPS's version, the contact law's
        damping and predicted restitutions, and the state the next stage starts from."""
        st, der, sc = self.st, self.der, self.scene
        d, snap = der["d"], self.snap
        w = measure.walls(snap)
        phi = None
        if self.stage == "pack":
            excl = sc["sampling"]["bulk_exclusion_d"] * d
            phi = measure.bulk(snap, w["y_bot"] + excl, w["y_top"] - excl, d)["phi"]
        out = self.common_sidecar("lammps", self.engines(), self.step() - st["iter0"], self.time(), w,
                                  snap.grain_overlaps_d(d), phi)
        law = contact.gran_hooke_history(sc, der)
        sm, sM = sc["material"]["size_ratio_min"], sc["material"]["size_ratio_max"]
        out.update(
            lammps_version=self.lammps_version,
            contact_law=dict(gamma_n=law["gamma_n"], gamma_t=law["gamma_t"], restitution_smallest_pair=
                             contact.pair_restitution(sc, der, sm * d, sm * d),
                             restitution_largest_pair=contact.pair_restitution(sc, der, sM * d, sM * d)),
            engine_state=dict(layout=self.lay, t_origin=st["t_origin"], strain=st["strain"], dt=st["dt"],
                              step=self.step()))
        return out
