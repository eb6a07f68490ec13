"""The stages and their controller (sampling, progress, checkpoints, guards).

Stages: pack, preshear, and the reversal stages, each a schedule of segments
(scene.segments): heaviside and sinusoidal are one segment, a reversal schedule
of the scene's `schedules` section several. A segment boundary falls between two
run chunks, where the controller writes the row just before a reversal and turns
the wall speed (at once, or through a per-step half cosine).

One controller per process, the class Stage, split by concern into one mixin per
module: packing (the pack's phases), shearing (wall speeds, reversal schedules),
sampling (engines, rows, guards, progress), checkpoint (reloads, checkpoints,
resume), outputs (final files, sidecar); this module holds the start and the run
loop. The controller runs inside a PyRunner at the sampling interval: writes one
CSV row, checks the guards, prints progress and, every run.checkpoint_every_s,
asks for a checkpoint. Its state lives in O.tags so that a checkpoint carries it
and a killed stage resumes exactly at its last checkpoint.

The run loop advances the simulation in chunks of about CHUNK_S of wall time
(`O.run(n)` stops after a whole step; runwait waits for it), cut at segment boundaries and at the
reload points (every checkpoint.RELOAD_EVERY steps), where the state is reloaded
and a checkpoint, if asked for, written. SIGTERM and SIGINT (see
`stagecli.install_signal_handlers`) only record themselves, whenever Python runs the handler
(during runwait's sleeps too), and are acted on at the end of the current chunk: the stage
goes back to the last reload point, checkpoints it and raises Interrupted (exit
code 4). Checkpoints are never written inside a step.
"""
import time

from yade.wrapper import Omega

import measure
import runwait
from checkpoint import Checkpoints
from outputs import Outputs
from packing import Packing
from sampling import Sampling
from shearing import Shearing
from stagecli import SIGNALS, interrupted
from stageerrors import GuardError, InputError  # noqa: F401  (run_stage's exit codes)
from workfiles import StageFiles

O = Omega()

CHUNK_S = 1.0  # wall time of one O.run chunk: the longest wait between a signal and its checkpoint


class Stage(StageFiles, Packing, Shearing, Sampling, Checkpoints, Outputs):
    def __init__(self, scene, scene_hash, stage, case_dir):
        super().__init__(scene, scene_hash, stage, case_dir)
        self.error = None
        self.want_checkpoint = False

    def close(self):
        """Nothing to close: YADE lives as long as the process (stagecli.run_stage calls it)."""

    def start_fresh(self):
        """The cell or the previous stage's state, the stage's plan and wall speeds (workfiles.StageFiles.fresh_state)."""
        st, steps_per_strain = self.fresh_state()
        if self.stage == "pack":
            self._start_pack(st)
        else:
            self._start_from_previous(st, steps_per_strain)
        w = measure.walls(self.lay)
        st["x_rel"] = w["x_top"] - w["x_bot"]
        st["gap"] = w["y_top"] - w["y_bot"]
        st["last_sample_iter"] = -1

    def run(self, lock=None):
        """Step to the end in chunks; checkpoint when due or on a signal.

        `lock.touch()` is called after every chunk (run_stage: renew the stage lock, keep
        the log at its path).
        """
        st = self.st
        # no row at the start itself: contact forces are not saved with a state, so the
        # first row comes one sampling interval in (the sidecar has the start's t and strain)
        chunk = 10  # steps; then sized from the measured rate to about CHUNK_S
        rate = None  # steps per wall second of the last chunk (runwait.run_and_wait)
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
            reload_at = self.next_reload()
            n = min(n, reload_at - (O.iter - st["iter0"]))
            i0, w0 = O.iter, time.time()
            if n > 0:
                rate = runwait.run_and_wait(O, n, rate)
            if self.error is not None:
                raise self.error
            if boundary is not None and O.iter - st["iter0"] >= boundary:
                self._enter_segment(st["segment"] + 1)
            elapsed = time.time() - w0
            if O.iter > i0:
                chunk = max(1, min(10 * chunk, int((O.iter - i0) * CHUNK_S / max(elapsed, 1e-3))))
            if lock is not None:
                lock.touch()
            done = O.iter - st["iter0"]
            if done >= reload_at and done < st["n_steps"] and not self.done:
                if self.want_checkpoint:  # checkpoints only where every run reloads (checkpoint.py)
                    self.want_checkpoint = False
                    self.checkpoint()
                self.reload()
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
        """A signal arrived: back to the last reload point, checkpoint there, raise Interrupted.

        The steps since that point are lost (at most RELOAD_EVERY) and done again, to the
        same bit, by the resumed run."""
        self.rewind()
        self.checkpoint()
        raise interrupted(f"iteration {O.iter}", self.st["rows"], self.partial)
