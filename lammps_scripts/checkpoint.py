"""Checkpoint and exact resume of a LAMMPS stage: its work files in `<case_dir>/.partial/<stage>/`
(yade_scripts/workfiles.py: the partial CSV, two checkpoint files in turn, resume.json).

A checkpoint is a LAMMPS restart file (`write_restart`: atoms, velocities, the contacts'
tangential history) plus resume.json, which carries the controller's state (`state`, the dict
st) and the layout; a rerun reads the restart file in a new process, sets the contact law, the
fixes and the computes up again from st, cuts the partial CSV back to the checkpoint's rows and
goes on.

Why a grid. A restart is not the live state bit for bit: LAMMPS's first run after reading it
starts with a setup (atoms sorted, neighbour lists built anew, forces computed again, the
dashpots from the full-step velocities where the live run has the half-step ones), so a run
resumed from a restart file taken at any step departs from the uninterrupted one, by 2e-3 U in
the grains' velocities after one step and by whole grain diameters after a few thousand (measured
on the tiny cell, docs/scene.md). So every run, interrupted or not, passes through that setup at
a fixed grid of steps, every GRID_EVERY steps since the stage's start (`grid_point`: the state
written to a restart file, `grid.lammps`, and the next run with `pre yes`), and checkpoints are
taken only at those points, by renaming that file: a resumed run then starts from exactly the
state the uninterrupted run continued from, through the same setup, and the two series are
byte-identical. A signal (SIGTERM, SIGINT) makes the last grid point the checkpoint (if it is
not one yet) and stops: the steps since then are run again, to the same bit, by the resumed run.

LAMMPS names the history's fix after a process-wide count of pair styles
(NEIGH_HISTORY_HH<n>), and a restart gives the history back only to a fix of the same name: so
one process runs one stage in one LAMMPS instance (a second instance, or `clear`, would count on
and drop the history), as run_stage.py does.

A mixin of stages.Stage.
"""
import json
import os
import time

import cell
import workfiles
from stagecli import SIGNALS, interrupted

GRID_EVERY = 10000  # steps between grid points, where every run goes through LAMMPS's setup
CHECKPOINTS = ("ckpt_a.lammps", "ckpt_b.lammps")  # written in turn
GRID_FILE = "grid.lammps"  # the last grid point's state


class Checkpoints:
    def resume_from(self, resume):
        """The state of resume.json's checkpoint: the restart file, the controller's state and
        layout, the contact law, computes and fixes as st says (the walls' velocities are the
        restart's), the CSV cut back to its rows; the next run starts with LAMMPS's setup."""
        cell.load_state(self.lmp, os.path.join(self.partial, resume["checkpoint"]))
        self.st, self.lay = resume["state"], resume["layout"]
        st = self.st
        st["resumed"] += 1
        workfiles.truncate_csv(self.csv_path, st["rows"])
        self.configure()
        self.setup_needed = True
        self.checkpoint_name = resume["checkpoint"]
        self.grid = None  # the checkpoint is the last grid point
        # the count of resumes kept with the checkpoint, so that a run stopped before its next one counts
        workfiles.write_resume(self.partial, resume["checkpoint"], st["rows"], resume["iter"], self.hash, state=st,
                               layout=self.lay)
        print(f"[{self.stage}] resumed from {resume['checkpoint']} at step {self.step()}, "
              f"strain {st['strain']:.5f}, {st['rows']} rows kept", flush=True)

    def next_grid(self):
        """Steps since the stage's start of the next grid point."""
        return ((self.step() - self.st["iter0"]) // GRID_EVERY + 1) * GRID_EVERY

    def grid_point(self):
        """The state now written to the grid file and kept with st (json) and the CSV's rows; the
        next run with LAMMPS's setup, as a run resumed from here starts. A checkpoint if one is due
        (run.checkpoint_every_s since the last)."""
        st = self.st
        self.account_time()
        st["last_grid"] = self.step()
        path = os.path.join(self.partial, GRID_FILE)
        tmp = path + ".tmp"
        self.lmp.command(f"write_restart {tmp}")
        os.replace(tmp, path)
        self.grid = json.dumps(st)
        self.setup_needed = True
        if time.time() - self.last_checkpoint >= self.scene["run"]["checkpoint_every_s"]:
            self.checkpoint()

    def account_time(self):
        """Wall and CPU time since the last account into st (carried by a checkpoint across resumes)."""
        st, now, cpu = self.st, time.time(), time.process_time()
        st["wall_time"] += now - self.t_wall0
        st["cpu_time"] += cpu - self.cpu0
        self.t_wall0, self.cpu0, self.iter_wall0 = now, cpu, self.step()

    def checkpoint(self):
        """The last grid point as the checkpoint: its rows on disk, the grid file renamed to the next
        checkpoint file, resume.json with its st and the layout. Nothing if it is one already."""
        if self.grid is None:
            return
        st = json.loads(self.grid)
        t0 = time.time()
        workfiles.sync(self.csv)
        name = workfiles.next_checkpoint(self.checkpoint_name, CHECKPOINTS)
        os.replace(os.path.join(self.partial, GRID_FILE), os.path.join(self.partial, name))
        it = st["last_grid"]
        workfiles.write_resume(self.partial, name, st["rows"], it, self.hash, state=st, layout=self.lay)
        self.checkpoint_name, self.grid, self.last_checkpoint = name, None, t0
        print(f"[{self.stage}] checkpoint at step {it} ({st['rows']} rows, written in {time.time() - t0:.2f} s)",
              flush=True)

    def interrupt_if_signalled(self):
        """A signal arrived: the last grid point becomes the checkpoint; raise Interrupted (exit 4)."""
        if not SIGNALS:
            return
        self.checkpoint()
        with open(os.path.join(self.partial, workfiles.RESUME)) as f:
            resume = json.load(f)
        raise interrupted(f"step {resume['iter']}", resume["rows"], self.partial)
