"""tools/engine_benchmark.py with real YADE and LAMMPS on the tiny cell: both engines pack the same
scene (the same disks), then paired pre-shears alternate which engine runs first, run the same
steps, and LAMMPS's ratio is its throughput over YADE's in the same pair; bare LAMMPS runs those
steps on each rank count the machine has, with LAMMPS's own timer shares.

Two pairs of a pre-shear of 0.02 strain (about 700 steps) on the H = 8d cell (211 disks); about 30 s.
"""
import os
import re
import shutil

import pandas as pd
import pytest

from tests.helpers import ROOT, yade

pytestmark = [pytest.mark.yade, pytest.mark.lammps]
TOOL = ROOT / "tools" / "engine_benchmark.py"


@pytest.fixture(scope="module")
def bench(tmp_path_factory):
    root = tmp_path_factory.mktemp("engine_bench")
    out = root / "engine_throughput.csv"
    r = yade(TOOL, "--out", out, "--work", root / "work", "--cells", "tiny", "--pairs", 2, "--strain", 0.02,
             "--ranks", "1,2")
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    return dict(out=out, stdout=r.stdout, runs=pd.read_csv(out), summary=pd.read_csv(root / "engine_throughput_summary.csv"),
                work=root / "work" / "tiny")


def test_pairs_run_both_engines_over_the_same_disks_and_steps_in_alternating_order(bench):
    stages = bench["runs"][bench["runs"]["kind"] == "stage"]
    assert list(stages["pair"]) == [1, 1, 2, 2] and list(stages["first"]) == ["yade", "yade", "lammps", "lammps"]
    assert stages["disks"].nunique() == 1 and stages["disks"].iloc[0] == 211 and stages["steps"].nunique() == 1
    for _, pair in stages.groupby("pair"):
        yade_, lammps = (pair[pair["engine"] == e].iloc[0] for e in ("yade", "lammps"))
        assert lammps["ratio_to_yade"] == pytest.approx(lammps["particle_steps_per_stage_cpu_s"]
                                                        / yade_["particle_steps_per_stage_cpu_s"])
        for run in (yade_, lammps):
            assert run["particle_steps_per_stage_cpu_s"] == pytest.approx(run["disks"] * run["steps"] / run["stage_cpu_s"])
            assert 0 < run["sampler_cpu_s"] < run["stage_cpu_s"] <= run["cpu_s"]


def test_bare_lammps_runs_the_stages_steps_on_each_rank_count_with_its_timer_shares(bench):
    runs = bench["runs"]
    bare = runs[runs["kind"] == "bare"]
    if list(bare["ranks"]) == [1]:   # 2 ranks left out: the reason is printed (no mpirun, one core, or busy cores)
        assert "bare LAMMPS not run on 2 ranks: " in bench["stdout"]
    else:
        assert list(bare["ranks"]) == [1, 2] and shutil.which("mpirun") and (os.cpu_count() or 1) >= 2
    assert (bare["steps"] == runs[runs["kind"] == "stage"]["steps"].iloc[0]).all()
    shares = bare[[c for c in bare.columns if c.endswith("_share")]]
    assert ((shares.sum(axis=1) - 1).abs() < 0.02).all() and ((shares >= 0) & (shares <= 1)).all().all()
    assert bare["pair_share"].iloc[0] > 0.1   # one rank: the contact forces are a good part of the work


def test_the_summary_gives_each_engines_median_the_paired_ratio_and_the_machines_load(bench):
    s = bench["summary"].set_index(["engine", "kind", "ranks"])
    lam = s.loc[("lammps", "stage", 1)]
    assert lam["runs"] == 2 and lam["ratio_min"] <= lam["ratio_median"] <= lam["ratio_max"]
    assert lam["particle_steps_per_cpu_s"] > 0 and s.loc[("yade", "stage", 1)]["particle_steps_per_cpu_s"] > 0
    assert lam["loadavg_start"] >= 0 and lam["cores"] >= 1
    assert "YADE's (paired" in bench["stdout"] and "load average (1 min)" in bench["stdout"]


def tool_module():
    import importlib.util
    spec = importlib.util.spec_from_file_location("engine_benchmark_tool", TOOL)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.skipif(shutil.which("mpirun") is None or (os.cpu_count() or 1) < 2, reason="needs mpirun and 2 cores")
def test_two_ranks_run_on_free_cores_and_are_left_out_naming_the_busy_cores():
    tool = tool_module()
    cores = os.cpu_count()
    assert tool.ranks_to_run([1, 2], busy=cores - 2 + 0.4) == ([1, 2], [])
    run, skipped = tool.ranks_to_run([1, 2], busy=cores - 2 + 0.6)
    assert run == [1] and skipped == [f"2 ranks: {cores - 2 + 0.6:.2f} of {cores} cores busy leaves fewer than 2 free"]
    assert tool.ranks_to_run([1, cores + 1], busy=0.0)[1] == [f"{cores + 1} ranks: {cores} cores"]


def test_the_busy_cores_are_read_from_the_cpu_times_between_zero_and_all_cores():
    busy = tool_module().busy_cores(window=0.2)
    assert 0.0 <= busy <= (os.cpu_count() or 1)


@pytest.mark.skipif(shutil.which("mpirun") is None, reason="needs mpirun")
def test_on_two_ranks_each_rank_holds_part_of_the_layer(bench):
    """The box is taller than the packed layer: cut across y (LAMMPS's own choice for a taller box), one rank
    held every disk and the other none; the cell is cut along x (lammps_scripts/cell.py: processors * 1 1).
    A correctness check, not a timing: it runs whether or not 2 cores are free."""
    work = bench["work"]
    with open(work / "bare_two_ranks.log", "w") as log:
        tool_module().bare(str(work / "scene_lammps.json"), str(work / "lammps" / "pack"), 50, 2,
                           str(work / "two_ranks"), log)
    text = (work / "two_ranks" / "bare_2" / "log.lammps").read_text()
    assert "1 by 2 by 1 MPI processor grid" not in text and "2 by 1 by 1 MPI processor grid" in text
    ave, most, least = re.search(r"Nlocal:\s+([0-9.]+) ave\s+([0-9]+) max\s+([0-9]+) min", text).groups()
    assert int(least) > 0.3 * float(ave) and int(most) < 1.7 * float(ave), (ave, most, least)
