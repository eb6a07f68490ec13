"""Sampling in LAMMPS: one CSV row per sample (rows.wall_row and measure.bulk), the guards,
progress lines. A mixin of stages.Stage (yade_scripts/sampling.py's rows and guards).
"""
import time

import measure
from rows import COLUMNS, fmt, pressure_window_problem, state_problem, wall_row
from stageerrors import GuardError


class Sampling:
    def sample(self):
        """One row of the state now (nothing if this step was sampled already)."""
        c0 = time.process_time()
        st, der, sc = self.st, self.der, self.scene
        it = self.step()
        if it == st["last_sample_iter"] and st["rows"] > 0:
            return
        snap = measure.Snapshot(self.lmp, self.lay, der["W"])
        w = measure.walls(snap)
        row, pw, gd = wall_row(der, st, w, self.time() - st["t_origin"])
        if sc["effects"]["measurements"]:
            excl = sc["sampling"]["bulk_exclusion_d"] * der["d"]
            b = measure.bulk(snap, w["y_bot"] + excl, w["y_top"] - excl, der["d"])
            b["sigma_xy_bulk"] /= der["p"]
            b["p_bulk"] /= der["p"]
            row.update(b)
        extra = []
        if self.stage == "pack":
            ke, wall_speed = self.ke_mean(snap), abs(w["v_top"]) / der["V0"]
            extra = [ke, wall_speed, st["load"] / (der["p"] * der["W"] * der["d"])]
        self.guards(row, snap, w, it)
        self.csv.write(",".join(fmt(row[c]) for c in COLUMNS) + "".join("," + fmt(x) for x in extra) + "\n")
        st["rows"] += 1
        st["last_sample_iter"] = it
        self.snap = snap
        if self.stage == "pack":
            self.pack_control(ke, wall_speed, pw)
        else:
            st["sum_p"] += pw
            st["sum_gap"] += row["gap"]
            st["sum_gd"] += abs(gd) * der["T0"]
            st["n_acc"] += 1
            if it >= st["fine_end"]:
                st["period"] = st["coarse_every"]
        now = time.time()
        if now - self.last_progress >= sc["run"]["progress_every_s"]:
            self.progress(now)
        st["sampler_cpu"] = st.get("sampler_cpu", 0.0) + time.process_time() - c0

    def guards(self, row, snap, w, it):
        """NaN, a disk out of the cell, an overlap above guards.max_overlap_d, the wall pressure's
        window mean off p (yade_scripts/sampling.py's guards)."""
        st, g, der = self.st, self.scene["guards"], self.der
        d = der["d"]
        why = state_problem(row, w, snap.y[: snap.N], d, f"step {it}")
        if why is not None:
            raise GuardError(why)
        ov = float(snap.delta.max()) / d if len(snap.delta) else 0.0
        if ov > g["max_overlap_d"]:
            raise GuardError(f"overlap {ov:.4f} d above guards.max_overlap_d = {g['max_overlap_d']:g} "
                             f"at step {it} (t = {row['t']:.4f})")
        if self.stage != "pack":
            why = pressure_window_problem(st, g, der, it - st["iter0"], row["p"])
            if why is not None:
                raise GuardError(why)

    def progress(self, now):
        st = self.st
        it = self.step()
        done = it - st["iter0"]
        elapsed = now - self.t_wall0
        rate = (it - self.iter_wall0) / elapsed if elapsed > 0 else 0.0
        eta = (st["n_steps"] - done) / rate if rate > 0 else float("nan")
        what = f"phase {st['phase']}" if self.stage == "pack" else f"strain {st['strain']:.4f}"
        print(f"[{self.stage}] {what} | {100.0 * done / st['n_steps']:5.1f}% | "
              f"t {(self.time() - st['t_origin']) / self.der['T0']:.2f} | {rate * self.lay['N']:.3g} particle-steps/s | "
              f"ETA {eta:.0f} s" + (" (at most)" if self.stage == "pack" else ""), flush=True)
        self.last_progress = now
