"""Checkpoint and resume: a stage's work files in `<case_dir>/.partial/<stage>/`.

A checkpoint is the simulation (O.save, the controller's state in O.tags["ys_state"])
plus the number of CSV rows it covers (resume.json); a rerun loads it, cuts the
partial CSV back to those rows and goes on, so the series has no gap and no
duplicated row. Two checkpoint files alternate, so a kill while saving leaves the
previous one whole. A mixin of stages.Stage.

A loaded state is not the live one bit for bit: YADE saves the contacts, but not
its collider's sorted bounds, so after a load the collider finds new contacts in
another order, the interaction container's order differs from the live run's
within a step or two, and so does the order in which contact forces are summed
on each disk (rounding: 1e-17 after a few steps, then chaos). So every run
reloads its own state at a fixed grid of steps, every RELOAD_EVERY steps since
the stage's start (`reload`: saved in memory, loaded back), and checkpoints are
taken only at those points: a resumed run then starts from exactly the state the
uninterrupted run continued from, and the two series are byte-identical. A
signal (SIGTERM, SIGINT) rewinds to the last reload point and checkpoints there.
"""
import json
import os
import shutil
import time

import build
import measure
import workfiles
from yade.wrapper import Omega

O = Omega()
RELOAD_EVERY = 10000  # steps between reloads (about 120 steps' cost each: ~1 %), the checkpoint grid
SLOT = "ys_reload"  # the in-memory save (O.saveTmp) of the last reload point
CHECKPOINTS = ("ckpt_a.yade.gz", "ckpt_b.yade.gz")  # written in turn


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



class Checkpoints:
    def prepare(self):
        os.makedirs(self.case_dir, exist_ok=True)
        resume = workfiles.resume_record(self.partial, self.csv_path, self.hash, self.stage)
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
            self.st = json.loads(O.tags["ys_state"])
            self.st["resumed"] += 1
            workfiles.truncate_csv(self.csv_path, self.st["rows"])
            print(f"[{self.stage}] resumed from {resume['checkpoint']} at iteration {O.iter}, "
                  f"strain {self.st['strain']:.5f}, {self.st['rows']} rows kept", flush=True)
        self.csv = open(self.csv_path, "a")
        self.t_wall0 = time.time()
        self.cpu0 = time.process_time()
        self.iter_wall0 = O.iter
        self.last_progress = self.t_wall0
        self.last_checkpoint = self.t_wall0
        self.reload()  # a fresh start too: a resume from this point sees the same state

    def checkpoint(self):
        st = self.st
        workfiles.sync(self.csv)
        now = time.time()
        st["wall_time"] += now - self.t_wall0
        st["cpu_time"] = st.get("cpu_time", 0.0) + time.process_time() - self.cpu0
        self.cpu0 = time.process_time()
        self.t_wall0, self.iter_wall0 = now, O.iter
        name = workfiles.next_checkpoint(st.get("ckpt"), CHECKPOINTS)
        st["ckpt"] = name
        O.tags["ys_state"] = json.dumps(st)
        save_state(os.path.join(self.partial, name))
        workfiles.write_resume(self.partial, name, st["rows"], O.iter, self.hash)
        self.last_checkpoint = now
        print(f"[{self.stage}] checkpoint at iteration {O.iter} ({st['rows']} rows, "
              f"written in {time.time() - now:.2f} s)", flush=True)

    def reload(self):
        """Save the state in memory, load it back, and set what a load does not restore (the
        wall load, a permanent force; the engines, built anew as at a resume): the state a
        resume from a checkpoint written here starts from. Between steps only."""
        O.tags["ys_state"] = json.dumps(self.st)
        O.saveTmp(SLOT)
        O.loadTmp(SLOT)
        self.lay = build.layout()
        O.dt = self.st["dt"]
        build.set_wall_load(self.lay, self.st["load"])
        self.bulk = measure.bulk_for(self.lay, self.der["d"])
        self._install_engines()

    def next_reload(self):
        """Steps since the stage's start of the next reload point."""
        return ((O.iter - self.st["iter0"]) // RELOAD_EVERY + 1) * RELOAD_EVERY

    def rewind(self):
        """Back to the last reload point (its state and controller state), to checkpoint there."""
        O.loadTmp(SLOT)
        self.st = json.loads(O.tags["ys_state"])
