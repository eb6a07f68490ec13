"""Performance of the DEM stages: throughput, cost of sampling, packing time.

    python3 tools/benchmark.py [--out results/accuracy/dem_throughput.csv] [--sizes 500,5000]

(standard library only; it runs `python3 yade_scripts/run_stage.py` per stage,
on one thread.) For each size (number of disks, set through H with W = 4H):
- pack: wall time of the packing (500 disks: the example's criteria; the
  5,000-disk cell uses loose criteria so the study stays within minutes);
- preshear at kappa = 1e3, I = 1e-3, sampled at the fine interval (0.001
  strain) throughout, with measurements on, then the same from the same
  packing with measurements off: particle-steps per second of each and the
  cost of sampling = wall(on)/wall(off) - 1, and, immune to other jobs on the
  machine, the sampler's own CPU time over the rest of the run's CPU time.
Prints the numbers and writes one CSV row per run.
"""
import argparse
import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "yade_scripts")
RUN = os.path.join(HERE, "run_stage.py")
H_FOR_N = {500: 12, 5000: 37}  # N = 0.8 W (H - d) / (pi <D^2>/4) with W = 4H
STRAIN_FOR_N = {500: 0.05, 5000: 0.01}


def scene_for(n, measurements):
    with open(os.path.join(HERE, "examples", "tiny.json")) as f:
        sc = json.load(f)
    H = H_FOR_N[n]
    sc["geometry"] = {"H_over_d": H, "W_over_H": 4}
    sc["loading"]["inertial_number"] = 1e-3
    sc["sampling"].update(fine_interval=0.001, fine_window=1.0, coarse_interval=0.01, bulk_exclusion_d=3)
    sc["preshear"]["strain"] = STRAIN_FOR_N[n]
    sc["effects"]["measurements"] = measurements
    sc["run"].update(checkpoint_every_s=10000, progress_every_s=10)
    sc["guards"]["pressure_window_strain"] = 100  # short runs: the pressure guard needs a full window
    if n > 1000:  # keep the packing of the big cell within minutes: loose criteria
        sc["pack"].update(initial_solid_fraction=0.5, compaction_pressure=0.2, ramp_time=5, ke_max=1e-4,
                          wall_speed_max=1e-2, pressure_tolerance=0.05)
    return sc


def run(scene, stage, case_dir):
    path = os.path.join(case_dir, f"scene_{stage}.json")
    with open(path, "w") as f:
        json.dump(scene, f)
    env = dict(os.environ, OMP_NUM_THREADS="1")
    t0 = time.time()
    r = subprocess.run(["python3", RUN, path, stage, case_dir], capture_output=True, text=True, env=env)
    wall = time.time() - t0
    if r.returncode != 0:
        sys.exit(f"{stage} failed ({r.returncode}):\n{r.stdout[-2000:]}\n{r.stderr[-2000:]}")
    with open(os.path.join(case_dir, f"{stage}.json")) as f:
        side = json.load(f)
    return side, wall


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=os.path.join("results", "accuracy", "dem_throughput.csv"))
    ap.add_argument("--sizes", default="500,5000")
    args = ap.parse_args()
    rows = []
    for n in [int(x) for x in args.sizes.split(",")]:
        work = tempfile.mkdtemp(prefix=f"dem_bench_{n}_")
        try:
            side, wall = run(scene_for(n, True), "pack", work)
            rows.append(dict(N=side["N"], stage="pack", measurements=True, steps=side["steps"],
                             samples=side["samples"], wall_time_s=side["wall_time_s"], process_time_s=wall,
                             particle_steps_per_s=side["particle_steps_per_s"], sampling_cost="",
                             sampler_cpu_over_rest=side["sampling_cost"]))
            print(f"N = {side['N']}: packing {side['wall_time_s']:.1f} s ({side['steps']} steps, "
                  f"{side['particle_steps_per_s']:.3g} particle-steps/s)", flush=True)
            res = {}
            for meas in (True, False):
                side, wall = run(scene_for(n, meas), "preshear", work)
                res[meas] = side
                os.rename(os.path.join(work, "preshear.json"), os.path.join(work, f"preshear_{meas}.json"))
            cost = res[True]["wall_time_s"] / res[False]["wall_time_s"] - 1
            inner = res[True]["sampling_cost"]  # sampler CPU / rest of the CPU: immune to a busy machine
            for meas in (True, False):
                s = res[meas]
                rows.append(dict(N=s["N"], stage="preshear", measurements=meas, steps=s["steps"],
                                 samples=s["samples"], wall_time_s=s["wall_time_s"], process_time_s="",
                                 particle_steps_per_s=s["particle_steps_per_s"],
                                 sampling_cost=cost if meas else "",
                                 sampler_cpu_over_rest=s["sampling_cost"]))
                print(f"N = {s['N']}: pre-shear, measurements {'on ' if meas else 'off'}: "
                      f"{s['particle_steps_per_s']:.3g} particle-steps/s ({s['steps']} steps, {s['samples']} samples, "
                      f"one every {s['sampling_steps']['fine']} steps)", flush=True)
            print(f"N = {res[True]['N']}: cost of sampling {100 * cost:+.1f}% (wall time on/off), "
                  f"{100 * inner:.1f}% (sampler CPU over the rest, same run)", flush=True)
        finally:
            shutil.rmtree(work, ignore_errors=True)
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    with open(args.out, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
