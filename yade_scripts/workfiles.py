"""A stage's work files in `<case_dir>/.partial/<stage>/` and its outputs in `<case_dir>`.

Pure Python (no YADE, no LAMMPS), shared by both engines' checkpoints and finish
(yade_scripts/checkpoint.py and outputs.py, lammps_scripts/checkpoint.py and outputs.py).

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
import os

from atomicfile import atomic_json

RESUME = "resume.json"


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
