"""Sampling: the engines with their sampler (a PyRunner at the sampling interval), one CSV
row per sample, the guards, progress lines.

The sampler runs inside a step: the positions are those of the end of the step while
O.iter and O.time are not yet incremented (`_sample` counts it so). A mixin of stages.Stage.
"""
import builtins
import time

from yade.wrapper import Omega

import engines
import measure
import packphases
from rows import fmt, pressure_window_problem, state_problem, wall_row
from stageerrors import GuardError

O = Omega()


class Sampling:
    def _install_engines(self):
        st = self.st
        builtins._ys_sample = self.sample
        builtins._ys_wall = self.wall_speed
        every = st["every"]
        # the sampler turns coarse right after the first sample at or past fine_end
        if self.stage != "pack" and st["last_sample_iter"] >= st["fine_end"]:
            every = st["coarse_every"]
        remaining_transition = 0
        if st.get("n_transition", 0) > 0:  # inside (or past) the current segment's half cosine
            remaining_transition = max(0, st["tr_iter0"] + st["n_transition"] + 1 - O.iter)
        # the pack's own Cundall damping, restored to effects.damping in the saved packing (finish)
        damping = packphases.damping(self.scene, st["phase"]) if self.stage == "pack" else None
        O.engines = engines.build(self.scene, every, "_ys_sample()",
                                  "_ys_wall()" if remaining_transition else None, remaining_transition,
                                  damping=damping)
        sampler = O.engines[-1]
        # PeriodicEngine keeps the in-step iteration (one less than the state it sees);
        # the grid of samples goes on from the last row (O.pause may act a step late)
        last = st["last_sample_iter"] if st["last_sample_iter"] >= 0 else st["iter0"]
        sampler.iterLast = last - 1
        sampler.nDone = 1  # else PeriodicEngine's first call resets iterLast to the current iteration
        self.sampler = sampler
        self.engine_names = engines.describe(O.engines)

    def sample(self):
        c0 = time.thread_time()  # CPU time of the simulation thread spent sampling
        try:
            self._sample(in_step=True)
        except BaseException as e:  # never let YADE swallow it: stop and re-raise in the main thread
            self.error = e
            O.pause()
        self.st["sampler_cpu"] = self.st.get("sampler_cpu", 0.0) + time.thread_time() - c0

    def _row(self, w):
        der = self.der
        d, p, W = der["d"], der["p"], der["W"]
        row, pw, gd = wall_row(der, self.st, w, self._t - self.st["t_origin"])
        ys = None
        if self.scene["effects"]["measurements"]:
            excl = self.scene["sampling"]["bulk_exclusion_d"] * d
            b = self.bulk.measure(self.lay, w["y_bot"] + excl, w["y_top"] - excl, W)
            ys = b.pop("ys")
            b["sigma_xy_bulk"] /= p
            b["p_bulk"] /= p
            row.update(b)
        return row, ys, pw, gd

    def _sample(self, in_step=False):
        """One row. Inside a step (PyRunner) the positions are already those of the
        end of the step while O.iter and O.time are not yet incremented: count it so."""
        self._it = O.iter + (1 if in_step else 0)
        self._t = O.time + (O.dt if in_step else 0.0)
        if self._it == self.st["last_sample_iter"]:
            return
        der, st, sc = self.der, self.st, self.scene
        w = measure.walls(self.lay)
        row, ys, pw, gd = self._row(w)
        extra = []
        if self.stage == "pack":
            ke_mean = self._ke_mean()
            wall_speed = abs(w["v_top"]) / der["V0"]
            row_load = st["load"] / (der["p"] * der["W"] * der["d"])
            extra = [ke_mean, wall_speed, row_load]
        self._guards(row, ys, w)
        self.csv.write(",".join(fmt(row[c]) for c in measure.COLUMNS)
                       + "".join("," + fmt(x) for x in extra) + "\n")
        st["rows"] += 1
        st["last_sample_iter"] = self._it
        if self.stage == "pack":
            self._pack_control(ke_mean, wall_speed, pw)
        else:
            st["sum_p"] += pw
            st["sum_gap"] = st.get("sum_gap", 0.0) + row["gap"]
            st["sum_gd"] += abs(gd) * der["T0"]
            st["n_acc"] += 1
            if self._it >= st["fine_end"] and self.sampler.iterPeriod != st["coarse_every"]:
                self.sampler.iterPeriod = st["coarse_every"]
        now = time.time()
        if now - self.last_progress >= sc["run"]["progress_every_s"]:
            self.progress(now)
        if now - self.last_checkpoint >= sc["run"]["checkpoint_every_s"] and not self.done:
            # saved at the end of the current chunk, between steps
            self.want_checkpoint = True

    def _guards(self, row, ys, w):
        st, g, der = self.st, self.scene["guards"], self.der
        d = der["d"]
        if ys is None:
            ys = self.bulk.ys()
        why = state_problem(row, w, ys, d, f"iteration {self._it}")
        if why is not None:
            raise GuardError(why)
        smax = self.scene["material"]["size_ratio_max"]
        if measure.max_overlap_d(d, smax) > g["max_overlap_d"]:
            ov = measure.exact_max_overlap_d(d)
            if ov > g["max_overlap_d"]:
                raise GuardError(f"overlap {ov:.4f} d above guards.max_overlap_d = {g['max_overlap_d']:g} "
                                 f"at iteration {self._it} (t = {row['t']:.4f})")
        if self.stage != "pack":
            why = pressure_window_problem(st, g, der, self._it - st["iter0"], row["p"])
            if why is not None:
                raise GuardError(why)

    def progress(self, now):
        st = self.st
        done = self._it - st["iter0"]
        pct = 100.0 * done / st["n_steps"]
        elapsed = now - self.t_wall0
        steps = self._it - self.iter_wall0
        rate = steps / elapsed if elapsed > 0 else 0.0
        pps = rate * self.lay["N"]
        eta = (st["n_steps"] - done) / rate if rate > 0 else float("nan")
        what = f"phase {st['phase']}" if self.stage == "pack" else f"strain {st['strain']:.4f}"
        print(f"[{self.stage}] {what} | {pct:5.1f}% | t {(self._t - st['t_origin']) / self.der['T0']:.2f} | "
              f"{pps:.3g} particle-steps/s | ETA {eta:.0f} s" + (" (at most)" if self.stage == "pack" else ""),
              flush=True)
        self.last_progress = now
