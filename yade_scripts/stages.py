"""The stages and their controller (sampling, progress, checkpoints, guards).

Stages: pack, preshear, and the reversal stages, each a schedule of segments
(scene.segments): heaviside and sinusoidal are one segment, a reversal schedule
of the scene's `schedules` section several. A segment boundary falls between two
run chunks, where the controller writes the row just before a reversal and turns
the wall speed (at once, or through a per-step half cosine).

One controller per process. It runs inside a PyRunner at the sampling interval:
writes one CSV row, checks the guards, prints progress and, every
run.checkpoint_every_s, asks for a checkpoint. Its state lives in O.tags so that a
checkpoint carries it and a killed stage resumes exactly at its last checkpoint.

The run loop advances the simulation in chunks of about CHUNK_S of wall time
(`O.run(n, True)` stops after a whole step). Python runs signal handlers only
between chunks (not while the main thread waits in YADE's C++), so SIGTERM and
SIGINT (see `install_signal_handlers`) are acted on at the end of the current
chunk: a checkpoint is written and the stage raises Interrupted (exit code 4).
Periodic checkpoints are written at chunk ends too, never inside a step.
"""
import builtins
import json
import math
import os
import re
import shutil
import signal
import time

import numpy as np
import yade
from yade.wrapper import Omega

import build
import engines
import measure
import scene as scenemod

O = Omega()
PREVIOUS = {"preshear": "pack"}  # every reversal stage (heaviside, sinusoidal, a schedule) starts from the pre-shear


class GuardError(RuntimeError):
    """A guard fired: the run stops with exit code 3."""


class InputError(RuntimeError):
    """A missing or mismatched input: exit code 2."""


class Interrupted(RuntimeError):
    """SIGTERM or SIGINT: a checkpoint was written, exit code 4; rerun to resume."""


CHUNK_S = 1.0  # wall time of one O.run chunk: the longest wait between a signal and its checkpoint
SIGNALS = []  # (signal number, time.time() when Python ran the handler) of each SIGTERM/SIGINT


def _on_signal(signum, frame):
    SIGNALS.append((signum, time.time()))


def install_signal_handlers():
    """SIGTERM and SIGINT only record themselves; the run loop checkpoints and stops.

    A SIGINT ignored by the parent (a background job of a non-interactive shell)
    stays ignored.
    """
    signal.signal(signal.SIGTERM, _on_signal)
    if signal.getsignal(signal.SIGINT) is not signal.SIG_IGN:
        signal.signal(signal.SIGINT, _on_signal)


def save_state(path):
    """O.save into an existing folder, through a temporary name.

    YADE 2023.02a's O.save into a missing folder does not fail but loops (for
    a large scene): the folder is created and checked first.
    """
    folder = os.path.dirname(path)
    os.makedirs(folder, exist_ok=True)
    if not os.path.isdir(folder):
        raise RuntimeError(f"cannot save {path}: {folder} is not a folder")
    tmp = os.path.join(folder, f"tmp{os.getpid()}_" + os.path.basename(path))  # keeps the .yade.gz suffix
    O.save(tmp)
    if not os.path.isfile(tmp):
        raise RuntimeError(f"O.save did not write {tmp}")
    os.replace(tmp, path)


def _atomic_json(path, obj):
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(obj, f, indent=1, sort_keys=True)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def _fmt(x):
    if isinstance(x, float):
        return repr(x) if math.isfinite(x) else "nan"
    return str(x)


class Stage:
    def __init__(self, scene, scene_hash, stage, case_dir):
        self.scene, self.hash, self.stage, self.case_dir = scene, scene_hash, stage, case_dir
        self.der = scenemod.derived(scene)
        self.partial = os.path.join(case_dir, ".partial", stage)
        self.csv_path = os.path.join(self.partial, f"{stage}.csv")
        self.resume_path = os.path.join(self.partial, "resume.json")
        self.error = None
        self.done = False
        self.want_checkpoint = False
        self.csv = None

    # ------------------------------------------------------------------ setup
    def prepare(self):
        os.makedirs(self.case_dir, exist_ok=True)
        resume = None
        if os.path.exists(self.resume_path):
            with open(self.resume_path) as f:
                resume = json.load(f)
            if resume.get("scene_sha256") != self.hash:
                print(f"[{self.stage}] partial run from another scene: discarded", flush=True)
                resume = None
            elif not self._csv_has_rows(resume["rows"]):
                print(f"[{self.stage}] partial CSV shorter than its checkpoint: discarded", flush=True)
                resume = None
        if resume is None:
            shutil.rmtree(self.partial, ignore_errors=True)  # this process owns the stage (see stagelock)
            os.makedirs(self.partial)
            self.start_fresh()
            self.st["resumed"] = 0
            with open(self.csv_path, "w") as f:
                f.write(",".join(self.columns()) + "\n")
        else:
            ck = os.path.join(self.partial, resume["checkpoint"])
            O.load(ck)
            self.lay = build.layout()
            self.st = json.loads(O.tags["ys_state"])
            self.st["resumed"] += 1
            self._truncate_csv(self.st["rows"])
            print(f"[{self.stage}] resumed from {resume['checkpoint']} at iteration {O.iter}, "
                  f"strain {self.st['strain']:.5f}, {self.st['rows']} rows kept", flush=True)
        O.dt = self.st["dt"]
        build.set_wall_load(self.lay, self.st["load"])
        self.bulk = measure.bulk_for(self.lay, self.der["d"])
        self.csv = open(self.csv_path, "a")
        self.t_wall0 = time.time()
        self.cpu0 = time.process_time()
        self.iter_wall0 = O.iter
        self.last_progress = self.t_wall0
        self.last_checkpoint = self.t_wall0
        self._install_engines()

    def columns(self):
        return measure.COLUMNS + (["ke", "wall_speed", "load"] if self.stage == "pack" else [])

    def _csv_has_rows(self, rows):
        if not os.path.isfile(self.csv_path):
            return False
        with open(self.csv_path) as f:
            n = sum(1 for line in f if line.endswith("\n"))
        return n >= rows + 1

    def _truncate_csv(self, rows):
        with open(self.csv_path) as f:
            lines = f.readlines()
        keep = lines[: rows + 1]
        with open(self.csv_path, "w") as f:
            f.writelines(keep)
            f.flush()
            os.fsync(f.fileno())

    def start_fresh(self):
        der, sc = self.der, self.scene
        smp = sc["sampling"]
        st = dict(stage=self.stage, rows=0, samples_p=[], sum_p=0.0, sum_gd=0.0, n_acc=0, wall_time=0.0,
                  window=[], pack_ok=0)
        self.st = st
        steps_per_strain = 1.0 / (der["gammadot"] * der["dt"])
        st["fine_every"] = max(1, int(round(smp["fine_interval"] * steps_per_strain)))
        st["coarse_every"] = max(st["fine_every"], int(round(smp["coarse_interval"] * steps_per_strain)))
        if self.stage == "pack":
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
        else:
            before = PREVIOUS.get(self.stage, "preshear")
            prev = os.path.join(self.case_dir, f"{before}.final.yade.gz")
            if not os.path.exists(prev):
                raise InputError(f"missing input {prev}: run stage {before} first")
            O.load(prev)
            self.lay = build.layout()
            pst = json.loads(O.tags["ys_state"])
            if pst.get("scene_sha256") != self.hash:
                print(f"[{self.stage}] warning: {prev} was made from another scene file", flush=True)
            st.update(dt=pst["dt"], t_origin=pst["t_origin"], strain=pst["strain"], iter0=O.iter,
                      time0=O.time, load=der["p"] * der["W"] * der["d"])
            if self.stage == "preshear":
                st["t_origin"] = O.time
                st["strain"] = 0.0
            st["strain_start"], st["t_start"] = st["strain"], (O.time - st["t_origin"]) / der["T0"]
            st["n_transition"] = 0
            if self.stage == "preshear":
                st["n_steps"] = int(math.ceil(sc["preshear"]["strain"] * steps_per_strain))
                st["fine_end"] = O.iter + int(math.ceil(smp["fine_window"] * steps_per_strain))
                build.set_wall_speeds(self.lay, der["U"], -der["U"])
            else:
                self._plan_schedule(steps_per_strain)
            st["every"] = st["fine_every"]
        w = measure.walls(self.lay)
        st["x_rel"] = w["x_top"] - w["x_bot"]
        st["gap"] = w["y_top"] - w["y_bot"]
        st["last_sample_iter"] = -1
        st["scene_sha256"] = self.hash
        self.st = st

    def _plan_schedule(self, steps_per_strain):
        """The reversal stage's segments in steps (scene.segments), and the start of the first.

        Segment k runs from step start_k = ceil(S_k * steps_per_strain) since the stage's start,
        S_k the strain at full rate of the segments before it, to start_{k+1}; a segment whose
        direction differs from the one before it (the pre-shear's, +1, for the first) starts
        with a reversal: sharp (heaviside) or a half cosine of the wall speed over
        ceil(transition_strain * steps_per_strain) steps.
        """
        st, smp = self.st, self.scene["sampling"]
        segs, at, plan = scenemod.segments(self.scene, self.stage), 0.0, []
        for seg in segs:
            n_tr = (int(math.ceil(seg["transition_strain"] * steps_per_strain))
                    if seg["transition"] == "half_cosine" else 0)
            plan.append(dict(seg, start=int(math.ceil(at * steps_per_strain)), n_transition=n_tr))
            at += seg["strain"]
        st["segments"], st["segment"], st["direction"] = plan, -1, 1
        st["n_steps"] = int(math.ceil(at * steps_per_strain))
        st["fine_window_steps"] = int(math.ceil(smp["fine_window"] * steps_per_strain))
        st["reversals"] = []
        self._enter_segment(0, at_start=True)

    def _next_boundary(self):
        """Steps since the stage's start at which the next segment begins (None: in the last one)."""
        st = self.st
        k = st.get("segment", -1) + 1
        if self.stage == "preshear" or self.stage == "pack" or k >= len(st["segments"]):
            return None
        return st["segments"][k]["start"]

    def _enter_segment(self, k, at_start=False):
        """Start segment k between two steps: a row for the state just before a reversal
        (not at the stage's start: its contact forces are not saved with the state), the
        new wall speeds (or the half cosine towards them), fine sampling from here on."""
        st, der = self.st, self.der
        seg = st["segments"][k]
        reverses = seg["direction"] != st["direction"]
        if reverses and not at_start:
            self._sample()
            if self.error is not None:
                raise self.error
        st["segment"] = k
        if reverses:
            st["reversals"].append(dict(strain=st["strain"], t=(O.time - st["t_origin"]) / der["T0"],
                                        direction=seg["direction"], transition=seg["transition"],
                                        **({"transition_strain": seg["transition_strain"]}
                                           if seg["transition"] == "half_cosine" else {})))
            st["tr_iter0"], st["tr_from"] = O.iter, st["direction"]
            # the pressure guard's window restarts at each reversal, as at the stage's start: the
            # wall pressure dips for a few percent of strain after every reversal, physically
            st["window"], st["guard_from"] = [], (O.iter - st["iter0"]) * der["dt"] * der["gammadot"]
            st["n_transition"] = seg["n_transition"]
            st["fine_end"] = O.iter + seg["n_transition"] + st["fine_window_steps"]
        st["direction"] = seg["direction"]
        U, d0 = der["U"], st.get("tr_from", 1)
        if reverses and seg["n_transition"] > 0:
            build.set_wall_speeds(self.lay, d0 * U, -d0 * U)  # the half cosine starts at the old speed
        else:
            build.set_wall_speeds(self.lay, seg["direction"] * U, -seg["direction"] * U)
        if not at_start and reverses:
            if seg["n_transition"] > 0:
                self._install_wall_runner(seg["n_transition"] + 1)
            sampler = self.sampler
            sampler.iterPeriod = st["fine_every"]
            sampler.iterLast = st["last_sample_iter"] - 1  # the fine grid starts at the reversal
            sampler.nDone = max(1, sampler.nDone)

    def _install_wall_runner(self, n):
        """A per-step PyRunner setting the wall speed for the next n steps, inserted before the sampler."""
        eng = [e for e in O.engines if e.label != "wallspeed"]
        k = next(i for i, e in enumerate(eng) if e.label in ("flip", "sampler"))
        O.engines = eng[:k] + [engines.PyRunner(command="_ys_wall()", iterPeriod=1, nDo=n, label="wallspeed")] + eng[k:]
        self.engine_names = engines.describe(O.engines)

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
        damping = self._pack_damping() if self.stage == "pack" else None
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

    # ------------------------------------------------------------ per sample
    def wall_speed(self):
        r"""Half cosine of the top wall speed from a U to b U over the transition, then b U.

        .. math:: u(x) = U\left[\tfrac12(a + b) + \tfrac12(a - b)\cos\pi x\right],\quad
                  x = \min(1, k / n_{tr})

        a, b the directions before and after the reversal, k the steps since its start
        (a = 1, b = -1: U cos(pi x), the sinusoidal protocol).
        """
        st = self.st
        k = O.iter + 1 - st["tr_iter0"]
        x = min(1.0, k / st["n_transition"])
        a, b = st["tr_from"], st["direction"]
        u = self.der["U"] * (0.5 * (a + b) + 0.5 * (a - b) * math.cos(math.pi * x))
        build.set_wall_speeds(self.lay, u, -u)

    def sample(self):
        c0 = time.thread_time()  # CPU time of the simulation thread spent sampling
        try:
            self._sample(in_step=True)
        except BaseException as e:  # never let YADE swallow it: stop and re-raise in the main thread
            self.error = e
            O.pause()
        self.st["sampler_cpu"] = self.st.get("sampler_cpu", 0.0) + time.thread_time() - c0

    def _row(self, w):
        der, st = self.der, self.st
        d, p, T0, V0, W = der["d"], der["p"], der["T0"], der["V0"], der["W"]
        gap = w["y_top"] - w["y_bot"]
        x_rel = w["x_top"] - w["x_bot"]
        st["strain"] += (x_rel - st["x_rel"]) / (0.5 * (gap + st["gap"]))
        st["x_rel"], st["gap"] = x_rel, gap
        gd = (w["u_top"] - w["u_bot"]) / gap
        sxy = (w["fx_bot"] - w["fx_top"]) / (2 * W * d) / p
        pw = (w["fy_top"] - w["fy_bot"]) / (2 * W * d) / p
        row = dict(t=(self._t - st["t_origin"]) / T0, strain=st["strain"], gammadot=gd * T0,
                   U_top=w["u_top"] / V0, U_bottom=w["u_bot"] / V0, gap=gap / d, sigma_xy=sxy, p=pw,
                   mu=abs(sxy) / pw if pw > 0 else math.nan,
                   inertial_number=abs(gd) * T0 / math.sqrt(pw) if pw > 0 else math.nan)
        for k in ("A_xx", "A_xy", "n_contacts", "sigma_xy_bulk", "p_bulk", "phi", "Z"):
            row[k] = math.nan
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
        self.csv.write(",".join(_fmt(row[c]) for c in measure.COLUMNS)
                       + "".join("," + _fmt(x) for x in extra) + "\n")
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

    def _guards(self, row, ys, w):
        st, g, der = self.st, self.scene["guards"], self.der
        d = der["d"]
        vals = [row[k] for k in ("strain", "sigma_xy", "p", "gap")] + [w["fx_top"], w["fy_top"]]
        if ys is None:
            ys = self.bulk.ys()
        if not all(math.isfinite(v) for v in vals) or not np.all(np.isfinite(ys)):
            raise GuardError(f"NaN in positions or forces at iteration {self._it} (t = {row['t']:.4f})")
        out = np.nonzero((ys < w["y_bot"]) | (ys > w["y_top"]))[0]
        if len(out):
            raise GuardError(f"disk {int(out[0])} left the cell at iteration {self._it} "
                             f"(y = {ys[out[0]] / d:.3f} d, walls at {w['y_bot'] / d:.3f} d and {w['y_top'] / d:.3f} d)")
        smax = self.scene["material"]["size_ratio_max"]
        if measure.max_overlap_d(d, smax) > g["max_overlap_d"]:
            ov = measure.exact_max_overlap_d(d)
            if ov > g["max_overlap_d"]:
                raise GuardError(f"overlap {ov:.4f} d above guards.max_overlap_d = {g['max_overlap_d']:g} "
                                 f"at iteration {self._it} (t = {row['t']:.4f})")
        if self.stage != "pack":
            elapsed = (self._it - st["iter0"]) * der["dt"] * der["gammadot"]
            win = st["window"]
            win.append([elapsed, row["p"]])
            span = g["pressure_window_strain"]
            while win and win[0][0] < elapsed - span:
                win.pop(0)
            if elapsed - st.get("guard_from", 0.0) >= span and len(win) >= 3:
                pm = sum(x[1] for x in win) / len(win)
                if abs(pm - 1) > g["pressure_tolerance"]:
                    raise GuardError(f"wall pressure {pm:.4f} p on average over the last {span:g} strain, "
                                     f"off by more than guards.pressure_tolerance = {g['pressure_tolerance']:g}")

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

    # ----------------------------------------------------------- checkpoints
    def checkpoint(self):
        st = self.st
        self.csv.flush()
        os.fsync(self.csv.fileno())
        now = time.time()
        st["wall_time"] += now - self.t_wall0
        st["cpu_time"] = st.get("cpu_time", 0.0) + time.process_time() - self.cpu0
        self.cpu0 = time.process_time()
        self.t_wall0, self.iter_wall0 = now, O.iter
        name = "ckpt_a.yade.gz" if st.get("ckpt") != "ckpt_a.yade.gz" else "ckpt_b.yade.gz"
        st["ckpt"] = name
        O.tags["ys_state"] = json.dumps(st)
        save_state(os.path.join(self.partial, name))
        _atomic_json(self.resume_path, dict(checkpoint=name, rows=st["rows"], iter=O.iter,
                                            scene_sha256=self.hash))
        self.last_checkpoint = now
        print(f"[{self.stage}] checkpoint at iteration {O.iter} ({st['rows']} rows, "
              f"written in {time.time() - now:.2f} s)", flush=True)

    # ------------------------------------------------------------------- run
    def run(self, lock=None):
        """Step to the end in chunks; checkpoint when due or on a signal.

        `lock` (a stagelock.StageLock) is renewed after every chunk.
        """
        st = self.st
        # no row at the start itself: contact forces are not saved with a state, so the
        # first row comes one sampling interval in (the sidecar has the start's t and strain)
        chunk = 10  # steps; then sized from the measured rate to about CHUNK_S
        while True:
            remaining = st["n_steps"] - (O.iter - st["iter0"])
            if remaining <= 0 or self.done:
                break  # a signal arriving now is ignored: the stage completes
            if SIGNALS:
                self.interrupt()
            n = min(remaining, chunk)
            boundary = self._next_boundary()
            if boundary is not None:
                n = min(n, boundary - (O.iter - st["iter0"]))
            i0, w0 = O.iter, time.time()
            if n > 0:
                O.run(n, True)
            if self.error is not None:
                raise self.error
            if boundary is not None and O.iter - st["iter0"] >= boundary:
                self._enter_segment(st["segment"] + 1)
            elapsed = time.time() - w0
            if O.iter > i0:
                chunk = max(1, min(10 * chunk, int((O.iter - i0) * CHUNK_S / max(elapsed, 1e-3))))
            if lock is not None:
                lock.touch()
            if self.want_checkpoint and not self.done:
                self.want_checkpoint = False
                self.checkpoint()
            if O.iter - i0 < n and not self.done and n > 0:
                raise RuntimeError(f"the run stopped early at iteration {O.iter}")
        if self.stage == "pack" and not self.done:
            raise GuardError(f"packing not converged within pack.max_time = {self.scene['pack']['max_time']:g} "
                             f"(phase {st['phase']}; see pack.csv columns ke, wall_speed, p)")
        self._sample()  # the final state is always sampled (no-op if just sampled)
        if self.error is not None:
            raise self.error
        self.finish()

    def interrupt(self):
        """A signal arrived: checkpoint now (between steps), then raise Interrupted."""
        self.checkpoint()
        name = signal.Signals(SIGNALS[0][0]).name
        raise Interrupted(f"{name} received: checkpoint at iteration {O.iter} ({self.st['rows']} rows) "
                          f"written in {self.partial}; run the same command again to resume")

    def finish(self):
        st, der, sc = self.st, self.der, self.scene
        self.csv.flush()
        os.fsync(self.csv.fileno())
        self.csv.close()
        st["wall_time"] += time.time() - self.t_wall0
        st["cpu_time"] = st.get("cpu_time", 0.0) + time.process_time() - self.cpu0
        O.tags["ys_state"] = json.dumps(st)
        final_tmp = os.path.join(self.partial, "final.yade.gz")
        save_state(final_tmp)
        side = self.sidecar()
        os.replace(final_tmp, os.path.join(self.case_dir, f"{self.stage}.final.yade.gz"))
        os.replace(self.csv_path, os.path.join(self.case_dir, f"{self.stage}.csv"))
        _atomic_json(os.path.join(self.case_dir, f"{self.stage}.json"), side)
        self._remove_work_files()
        print(f"[{self.stage}] done: {st['rows']} samples, {O.iter - st['iter0']} steps, "
              f"{side['wall_time_s']:.1f} s, {side['particle_steps_per_s']:.3g} particle-steps/s", flush=True)

    def _remove_work_files(self):
        """Remove this stage's own work files, then its folder if nothing else is in it.

        Own files: the checkpoints, resume.json and the temporary saves of save_state
        (`tmp<pid>_*.yade.gz`, left behind only by a process killed while saving).
        """
        names = ["ckpt_a.yade.gz", "ckpt_b.yade.gz", "resume.json", "resume.json.tmp"]
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
            stage=self.stage, scene=sc, scene_sha256=self.hash, seed=sc["seed"], N=self.lay["N"],
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
            columns=self.columns())
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
            if self.stage in ("heaviside", "sinusoidal"):
                out.update(reversal_strain=st["strain_start"], reversal_t=st["t_start"])
            elif self.stage != "preshear":   # a schedule: every reversal, the first also as reversal_strain, _t
                out.update(reversal_strain=st["reversals"][0]["strain"], reversal_t=st["reversals"][0]["t"],
                           reversals=st["reversals"], segments=[
                               {k: v for k, v in seg.items() if k not in ("start", "n_transition")}
                               for seg in st["segments"]])
            if self.stage == "sinusoidal":
                out["transition_steps"] = st["n_transition"]
        return out
