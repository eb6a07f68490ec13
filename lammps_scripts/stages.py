"""The LAMMPS stages and their controller: pack, preshear and every reversal stage of the wall cell.

One controller per process, the class Stage, split by concern into one mixin per module as in
yade_scripts/: packing (the pack's phases), shearing (the previous state, the walls' speeds,
the reversal protocol), sampling (rows, guards, progress), checkpoint (the grid of setups,
checkpoints, resume, signals), outputs (final files, sidecar); this module holds the start and
the run loop. LAMMPS runs between samples (`run n`, `pre no` unless a fix, the pair style
or the load changed since the last run, whose setup LAMMPS then needs), cut at a reversal
stage's segment boundaries and one step at a time through a half cosine (shearing.py); Python
samples between runs: one CSV row, the guards, progress.

Not run (docs/scene.md, "The LAMMPS engine"; refusals.py): the periodic cell, gravity, Cundall
damping, rolling resistance.
"""
import os
import shutil
import time

import cell
import lammpslib
import measure
import workfiles
from checkpoint import Checkpoints
from outputs import Outputs
from packing import Packing
from sampling import Sampling
from shearing import Shearing
from stageerrors import GuardError, InputError  # noqa: F401  (run_stage's exit codes)


class Stage(workfiles.StageFiles, Packing, Shearing, Sampling, Checkpoints, Outputs):
    def __init__(self, scene, scene_hash, stage, case_dir):
        super().__init__(scene, scene_hash, stage, case_dir)
        self.setup_needed = True
        self.drag = None
        self.lmp = None
        self.grid = None  # the last grid point's st (json), until it is a checkpoint (checkpoint.py)
        self.checkpoint_name = None

    def step(self):
        return int(self.lmp.extract_global("ntimestep"))

    def time(self):
        """Simulated time since the packing's start, s (the step count times the frozen dt)."""
        return self.step() * self.st["dt"]

    def prepare(self):
        """The work folder, LAMMPS (logging into it), then a resume from the stage's checkpoint if it
        has one (checkpoint.py), else a fresh start."""
        os.makedirs(self.case_dir, exist_ok=True)
        resume = workfiles.resume_record(self.partial, self.csv_path, self.hash, self.stage)
        if resume is None:
            shutil.rmtree(self.partial, ignore_errors=True)  # this process owns the stage (stagelock)
            os.makedirs(self.partial)
        self.lmp = lammpslib.open_lammps(("-log", os.path.join(self.partial, "log.lammps"), "-screen", "none",
                                          "-nocite"))
        self.lammps_version = self.lmp.version()
        measure.check_image_flags(self.lmp)
        self.t_wall0, self.cpu0 = time.time(), time.process_time()
        self.last_progress = self.last_checkpoint = self.t_wall0
        if resume is None:
            self.start_fresh()
        else:
            self.resume_from(resume)
        self.iter_wall0 = self.step()
        self.csv = open(self.csv_path, "a")
        if resume is None:
            self.grid_point()  # the stage's start: a resume from here sees the same state

    def start_fresh(self):
        """The cell or the previous stage's state, the stage's plan, the contact law, computes,
        fixes and the walls' speeds; the forces of the start; the CSV's header."""
        der = self.der
        st, steps_per_strain = self.fresh_state()
        if self.stage == "pack":
            self.start_pack(st)
        else:
            self.start_from_previous(st, steps_per_strain)
        self.configure()
        self.apply_wall_speeds()
        self.run_steps(0)  # forces of the start (the walls' contact forces for the first strain step)
        w = measure.walls(measure.Snapshot(self.lmp, self.lay, der["W"]))
        st["x_rel"], st["gap"] = w["x_top"] - w["x_bot"], w["y_top"] - w["y_bot"]
        st["last_sample_iter"] = st["iter0"]
        st["period"] = st["every"]
        with open(self.csv_path, "w") as f:
            f.write(",".join(self.columns()) + "\n")

    def configure(self):
        """The contact law at st's friction, the computes, the fixes with st's wall load and, in the
        pack, the grains' drag of st's phase: what a restart file does not hold."""
        st = self.st
        self.pair_style = cell.interactions(self.lmp, self.scene, self.der, st["friction"])
        measure.computes(self.lmp)
        self.fix_lines = cell.fixes(self.lmp, self.lay["n_wall"], st["load"])
        if self.stage == "pack":
            self.apply_damping()

    def run_steps(self, n):
        """`run n`, with LAMMPS's setup only when something changed since the last run."""
        pre = "yes" if self.setup_needed else "no"
        self.lmp.command(f"run {n} pre {pre} post no")
        self.setup_needed = False

    def run(self, lock=None):
        """Step to the end; `lock.touch()` after every run (run_stage).

        A run ends at the next sample (every st['period'] steps since the last one), at the next
        segment's start (a reversal stage's boundary, where `enter_segment` turns the walls), at
        the next grid point (checkpoint.py) or after one step inside a half cosine (whose speed is
        set after every step). A signal is acted on between two runs."""
        st = self.st
        while not self.done:
            done = self.step() - st["iter0"]
            if done >= st["n_steps"]:
                break  # a signal arriving now is ignored: the stage completes
            self.interrupt_if_signalled()
            transition = self.in_transition()
            grid = self.next_grid()
            n = min(st["n_steps"] - done, st["last_sample_iter"] + st["period"] - self.step(), grid - done)
            boundary = self.next_boundary()
            if boundary is not None:
                n = min(n, boundary - done)
            self.run_steps(1 if transition else max(1, n))
            if transition:
                self.follow_transition()
            if self.step() >= st["last_sample_iter"] + st["period"]:
                self.sample()
            while (boundary := self.next_boundary()) is not None and self.step() - st["iter0"] >= boundary:
                self.enter_segment(st["segment"] + 1)
            if lock is not None:
                lock.touch()
            if self.step() - st["iter0"] == grid and grid < st["n_steps"] and not self.done:
                self.grid_point()
        if self.stage == "pack" and not self.done:
            raise GuardError(f"packing not converged within pack.max_time = {self.scene['pack']['max_time']:g} "
                             f"(phase {st['phase']}; see pack.csv columns ke, wall_speed, p)")
        self.sample()  # the final state is always sampled (no-op if just sampled)
        self.finish()

    def close(self):
        if self.lmp is not None:
            lammpslib.close_lammps(self.lmp)
            self.lmp = None
