"""tools/stage_benchmark.py with real YADE on the tiny cell: the stage and bare YADE run the same
steps from the same packing with the same engines, so their final states are the same to the bit.

Two pairs of a pre-shear of 0.02 strain (about 700 steps: fewer than one reload interval, after
which the stage's reload reorders the contacts) on the H = 8d cell; about 20 s.
"""
import subprocess

import pandas as pd
import pytest

from tests.helpers import ROOT, YS, command, yade

TOOL = ROOT / "tools" / "stage_benchmark.py"
PAIR_COLUMNS = ["pair", "first", "steps", "cpu_stage_s", "cpu_bare_s", "wall_stage_s", "wall_bare_s",
                "cpu_ratio", "wall_ratio", "nvcsw_stage", "nvcsw_bare", "nivcsw_stage", "nivcsw_bare",
                "same_final_state"]


@pytest.fixture(scope="module")
def bench(tmp_path_factory):
    root = tmp_path_factory.mktemp("stage_bench")
    out, work = root / "stage_overhead.csv", root / "work"
    r = yade(TOOL, "--out", out, "--work", work, "--pairs", 2, "--h-over-d", 8, "--strain", 0.02,
             "--inertial-number", 1e-2)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    return dict(out=out, work=work, stdout=r.stdout)


def digests(*states):
    r = subprocess.run(command(TOOL, "digest", *states), capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-2000:]
    return [line.split()[1] for line in r.stdout.splitlines() if line.startswith("DIGEST ")]


def test_every_pair_ran_the_same_steps_to_the_same_final_state_in_alternating_order(bench):
    pairs = pd.read_csv(bench["out"])
    assert list(pairs.columns) == PAIR_COLUMNS
    assert list(pairs["pair"]) == [1, 2] and list(pairs["first"]) == ["stage", "bare"]
    reload_every = int(next(line for line in (YS / "checkpoint.py").read_text().splitlines()
                            if line.startswith("RELOAD_EVERY")).split("=")[1].split("#")[0])
    assert (pairs["steps"] > 100).all() and (pairs["steps"] < reload_every).all()
    assert pairs["same_final_state"].all()
    assert (pairs["cpu_ratio"] == pairs["cpu_stage_s"] / pairs["cpu_bare_s"]).all()
    assert (pairs["wall_ratio"] == pairs["wall_stage_s"] / pairs["wall_bare_s"]).all()


def test_the_state_digest_tells_the_packing_from_the_sheared_state(bench):
    work = bench["work"]
    pack, stage, bare = digests(work / "pack" / "pack.final.yade.gz", work / "stage" / "preshear.final.yade.gz",
                                work / "bare" / "bare.final.yade.gz")
    assert stage == bare  # the profiled stage and the timed bare run: timers change nothing
    assert pack != stage


def test_the_summary_and_the_wall_breakdown_are_written_and_printed(bench):
    summary = pd.read_csv(bench["out"].with_name("stage_overhead_summary.csv")).set_index("quantity")
    assert list(summary.index) == ["cpu_ratio", "wall_ratio"]
    assert (summary["pairs"] == 2).all()
    assert ((summary["min"] <= summary["median"]) & (summary["median"] <= summary["max"])).all()
    wall = pd.read_csv(bench["out"].with_name("stage_overhead_wall.csv"))
    parts = set(zip(wall["run"], wall["part"]))
    for run in ("stage", "bare"):
        assert {(run, "O.run: engines (physics)"), (run, "O.run: outside the engines"),
                (run, "the whole process")} <= parts
    assert ("stage", "O.run: PyRunners (sampler)") in parts
    assert "cpu_ratio (stage / bare YADE, 2 pairs): median" in bench["stdout"]
    assert "wall_ratio (stage / bare YADE, 2 pairs): median" in bench["stdout"]
