"""A stage's work files (yade_scripts/workfiles.py), which both engines' checkpoints and finish use:
which partial run a rerun resumes, how the CSV is cut back, the checkpoint files taken in turn, and
the outputs published sidecar last. Pure Python, constructed files; the real resumes are in
test_dem_stages.py (YADE) and test_lammps_stages.py (LAMMPS)."""
import importlib
import json
import sys

from tests.helpers import YS


def load_workfiles():
    """yade_scripts/workfiles.py with its sibling atomicfile.py, yade_scripts/ on sys.path only meanwhile."""
    sys.path.insert(0, str(YS))
    try:
        return importlib.import_module("workfiles")
    finally:
        sys.path.remove(str(YS))


workfiles = load_workfiles()


def partial_run(tmp_path, rows_written, scene_sha="abc", checkpoint_rows=2):
    partial = tmp_path / ".partial" / "preshear"
    partial.mkdir(parents=True)
    csv = partial / "preshear.csv"
    csv.write_text("t,strain\n" + "".join(f"{k},{k / 10}\n" for k in range(rows_written)) + "9,0.")  # a torn last row
    workfiles.write_resume(partial, "ckpt_a.lammps", checkpoint_rows, 1000, scene_sha, state={"rows": checkpoint_rows})
    return partial, csv


def test_a_rerun_resumes_a_partial_run_of_its_own_scene_whose_csv_holds_the_checkpoints_rows(tmp_path):
    partial, csv = partial_run(tmp_path, rows_written=3)
    resume = workfiles.resume_record(partial, csv, "abc", "preshear")
    assert resume == dict(checkpoint="ckpt_a.lammps", rows=2, iter=1000, scene_sha256="abc", state={"rows": 2})
    workfiles.truncate_csv(csv, resume["rows"])
    assert csv.read_text() == "t,strain\n0,0.0\n1,0.1\n"   # rows past the checkpoint and the torn one gone


def test_a_partial_run_of_another_scene_or_with_a_csv_short_of_its_checkpoint_is_started_afresh(tmp_path, capsys):
    partial, csv = partial_run(tmp_path / "a", rows_written=3)
    assert workfiles.resume_record(partial, csv, "other", "preshear") is None
    partial, csv = partial_run(tmp_path / "b", rows_written=1)
    assert workfiles.resume_record(partial, csv, "abc", "preshear") is None
    assert workfiles.resume_record(tmp_path / "none", tmp_path / "none.csv", "abc", "preshear") is None
    said = capsys.readouterr().out
    assert "partial run from another scene: discarded" in said and "partial CSV shorter than its checkpoint" in said


def test_checkpoint_files_are_written_in_turn():
    names = ("ckpt_a.lammps", "ckpt_b.lammps")
    assert [workfiles.next_checkpoint(p, names) for p in (None, "ckpt_a.lammps", "ckpt_b.lammps")] == [
        "ckpt_a.lammps", "ckpt_b.lammps", "ckpt_a.lammps"]


def test_a_completed_stage_is_published_into_the_case_folder_sidecar_last(tmp_path):
    partial = tmp_path / ".partial" / "heaviside"
    partial.mkdir(parents=True)
    (partial / "final.lammps").write_text("state")
    (partial / "heaviside.csv").write_text("t\n1\n")
    workfiles.publish(tmp_path, "heaviside", partial / "final.lammps", ".final.lammps", partial / "heaviside.csv",
                      {"samples": 1})
    assert (tmp_path / "heaviside.final.lammps").read_text() == "state"
    assert (tmp_path / "heaviside.csv").read_text() == "t\n1\n"
    assert json.loads((tmp_path / "heaviside.json").read_text()) == {"samples": 1}
    assert not (partial / "final.lammps").exists() and not (partial / "heaviside.csv").exists()
