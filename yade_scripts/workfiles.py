"""A stage's work files in `<case_dir>/.partial/<stage>/` and its outputs in `<case_dir>`.

Pure Python (no YADE, no LAMMPS), shared by both engines' stages: `StageFiles`, the base of their
stages.Stage (the stage's folders, CSV columns and the sidecar's common keys), and the checkpoints'
and the finish's file handling (yade_scripts/checkpoint.py and outputs.py,
lammps_scripts/checkpoint.py and outputs.py).

Work files: the partial CSV (every row so far), two checkpoint files written in turn (a kill
while one is written leaves the other whole) and `resume.json`, written atomically after its
checkpoint file: {checkpoint: the file's name, rows: the CSV rows it covers, iter: its step,
scene_sha256, ...}. A rerun resumes from it only if it was made from the same scene file and
the CSV holds at least its rows; it cuts the CSV back to them, so the series has no gap and no
duplicated row.

Outputs: `<stage><state suffix>` (the final state), `<stage>.csv` and `<stage>.json` (the
sidecar), renamed into `<case_dir>` only once the stage is complete (`publish`).
"""
import json
import math
import os

import protocol
import scene as scenemod
from atomicfile import atomic_json
from rows import COLUMNS, PACK_COLUMNS, overlap_stats

RESUME = "resume.json"


class StageFiles:
    """A stage of a case and its files: the scene (and its hash and derived values), the stage's
    name, the case folder, the work folder `.partial/<stage>/` and the partial CSV in it; the CSV's
    columns. The base of both engines' stages.Stage."""

    def __init__(self, scene, scene_hash, stage, case_dir):
        self.scene, self.hash, self.stage, self.case_dir = scene, scene_hash, stage, case_dir
        self.der = scenemod.derived(scene)
        self.partial = os.path.join(case_dir, ".partial", stage)
        self.csv_path = os.path.join(self.partial, f"{stage}.csv")
        self.done = False
        self.csv = None

    def fresh_state(self):
        """The controller's state ``self.st`` at a fresh start: counters at zero and the sampling
        intervals in steps at the nominal rate (sampling.fine_interval and coarse_interval times
        steps_per_strain = 1 / (gammadot dt)); returns (st, steps_per_strain)."""
        der, smp = self.der, self.scene["sampling"]
        st = dict(stage=self.stage, rows=0, sum_p=0.0, sum_gd=0.0, sum_gap=0.0, n_acc=0, window=[], pack_ok=0,
                  resumed=0, scene_sha256=self.hash, wall_time=0.0, cpu_time=0.0)
        steps_per_strain = 1.0 / (der["gammadot"] * der["dt"])
        st["fine_every"] = max(1, int(round(smp["fine_interval"] * steps_per_strain)))
        st["coarse_every"] = max(st["fine_every"], int(round(smp["coarse_interval"] * steps_per_strain)))
        self.st = st
        return st, steps_per_strain

    def columns(self):
        """The CSV's columns: the contract's, and the pack's own after them in pack.csv."""
        return COLUMNS + (PACK_COLUMNS if self.stage == "pack" else [])

    def common_sidecar(self, engine, engines, steps, t, w, overlaps_d, phi=None):
        """The sidecar's keys both engines write (docs/data-contract.md), from the stage's state
        ``self.st`` and layout ``self.lay``.

        Parameters
        ----------
        engine : str
            "yade" or "lammps"; ``engines``: what acts every step (YADE's engines, LAMMPS's pair
            style and fixes).
        steps : int
            Steps the stage ran; ``t``: the simulated time now, s.
        w : dict
            The walls now (measure.walls, SI).
        overlaps_d : list
            The grain-grain contacts' overlaps now, in d (overlap_end_d).
        phi : float, optional
            The pack's: the bulk band's solid fraction now.
        """
        st, der, sc = self.st, self.der, self.scene
        d, p, T0 = der["d"], der["p"], der["T0"]
        n_p = max(1, st["n_acc"])
        p_mean = st["sum_p"] / n_p if st["n_acc"] else math.nan
        sampler = st.get("sampler_cpu", 0.0)
        out = dict(
            stage=self.stage, engine=engine, scene=sc, scene_sha256=self.hash, seed=sc["seed"], N=self.lay["N"],
            N_wall=self.lay["n_wall"], dt=st["dt"], dt_over_tc=st["dt"] / der["tc"], kn=der["kn"], kt=der["kt"],
            kappa=sc["material"]["kappa"], inertial_number=sc["loading"]["inertial_number"],
            U=der["U"], gammadot_nominal=der["gammadot"], time_unit_s=T0,
            steps=steps, samples=st["rows"], engines=engines, wall_time_s=st["wall_time"],
            particle_steps_per_s=self.lay["N"] * steps / st["wall_time"] if st["wall_time"] > 0 else math.nan,
            cpu_time_s=st["cpu_time"], sampler_cpu_s=sampler,
            sampling_cost=sampler / max(1e-12, st["cpu_time"] - sampler),
            resumed=st["resumed"], t_end=(t - st["t_origin"]) / T0, strain_end=st["strain"],
            gap_end=(w["y_top"] - w["y_bot"]) / d,
            sampling_steps=dict(fine=st["fine_every"], coarse=st["coarse_every"], every=st["every"]),
            columns=self.columns(), overlap_end_d=overlap_stats(overlaps_d))
        if self.stage == "pack":
            pw = (w["fy_top"] - w["fy_bot"]) / (2 * der["W"] * d) / p
            out.update(phi=phi, gap=out["gap_end"], converged_at_t=st.get("converged_at_t"),
                       phase_steps=st.get("phase_steps", {}), p_wall_end=pw, kappa_achieved=der["kn"] / (pw * p * d))
        else:
            out.update(strain_start=st["strain_start"], t_start=st["t_start"], p_wall_mean=p_mean,
                       kappa_achieved=der["kn"] / (p_mean * p * d),
                       inertial_number_achieved=(st["sum_gd"] / n_p) / math.sqrt(p_mean),
                       gap_mean=st.get("sum_gap", math.nan) / n_p)
            out.update(protocol.sidecar_keys(self.stage, st))
        return out


def resume_record(partial, csv_path, scene_hash, stage):
    """The stage's resume.json as a dict, or None (a fresh start) when there is none, it was made
    from another scene file or the partial CSV is shorter than its rows (the reason printed)."""
    path = os.path.join(partial, RESUME)
    if not os.path.exists(path):
        return None
    with open(path) as f:
        resume = json.load(f)
    if resume.get("scene_sha256") != scene_hash:
        print(f"[{stage}] partial run from another scene: discarded", flush=True)
        return None
    if not csv_has_rows(csv_path, resume["rows"]):
        print(f"[{stage}] partial CSV shorter than its checkpoint: discarded", flush=True)
        return None
    return resume


def write_resume(partial, checkpoint, rows, it, scene_hash, **extra):
    """resume.json for the checkpoint file ``checkpoint`` (a name in ``partial``), written atomically."""
    atomic_json(os.path.join(partial, RESUME), dict(checkpoint=checkpoint, rows=rows, iter=it,
                                                    scene_sha256=scene_hash, **extra))


def next_checkpoint(previous, names):
    """The checkpoint file to write next: the first of the two ``names`` unless it was the previous one."""
    return names[0] if previous != names[0] else names[1]


def csv_has_rows(csv_path, rows):
    """True when the CSV at ``csv_path`` holds its header and at least ``rows`` whole rows."""
    if not os.path.isfile(csv_path):
        return False
    with open(csv_path) as f:
        n = sum(1 for line in f if line.endswith("\n"))
    return n >= rows + 1


def truncate_csv(csv_path, rows):
    """Cut the CSV back to its header and its first ``rows`` rows, on disk before returning."""
    with open(csv_path) as f:
        lines = f.readlines()
    with open(csv_path, "w") as f:
        f.writelines(lines[: rows + 1])
        f.flush()
        os.fsync(f.fileno())


def sync(f):
    """Flush the open file ``f`` to disk (a checkpoint's rows, or the finished CSV)."""
    f.flush()
    os.fsync(f.fileno())


def publish(case_dir, stage, final_state, state_suffix, csv_path, sidecar):
    """A completed stage's outputs into ``case_dir``: the final state file (written in the work
    folder), the CSV, then the sidecar (atomically) last, so that a sidecar stands for a complete
    stage."""
    os.replace(final_state, os.path.join(case_dir, stage + state_suffix))
    os.replace(csv_path, os.path.join(case_dir, f"{stage}.csv"))
    atomic_json(os.path.join(case_dir, f"{stage}.json"), sidecar)
