"""Throughput of the two DEM engines side by side: YADE's pre-shear stage against LAMMPS's, paired.

    python3 tools/engine_benchmark.py [--out results/accuracy/engine_throughput.csv] [--cells quick,paper]
        [--pairs 2] [--ranks 1,2] [--sampling JSON] [--work DIR]

(standard library only; the children run the stages, YADE and LAMMPS each imported as a library by
its own runner, on one thread.) For each cell of CELLS (the quick preset's narrow cell, 626 disks,
and the paper's W = 4H cell, about 5,000 disks; both H = 37d, kappa 1e3, I = 5e-3, dt = 0.1 t_c,
e = 0.5, friction 0.45, the disks placed by seed 1):

- each engine packs the same scene (the same disks at the same loose places, placement.py; the big
  cell with loose criteria so that it packs in minutes);
- P pairs of the pre-shear of the cell's strain, each engine from its own packing, in the order
  YADE, LAMMPS, then LAMMPS, YADE, alternately (a load that changes during the run shifts both);
  per run: the process's CPU time (user + sys of the child, getrusage RUSAGE_CHILDREN), its wall
  time, and the stage's own CPU time and sampler CPU time from its sidecar;
- LAMMPS alone, bare (`lmp`, no Python: the stage's contact law, fixes and wall speeds from its
  own packing, one `run n`), at each number of MPI ranks of ``--ranks`` (`mpirun -np R`; more than
  one only where `mpirun` exists and that many cores are free: `ranks_to_run`): its CPU time, and
  where LAMMPS's time goes from its own timer table (Pair, Neigh, Comm, Output, Modify, Other).

Particle-steps per CPU second = N steps / CPU s, N the grains (not the walls' disks), of the
stage's own CPU time (from the stage's start to its end, the process start and imports left out:
YADE's import costs about a second) and of the whole process. The ratio is LAMMPS's over YADE's,
per pair. Printed, and written: ``--out`` one row per run, ``<out>_summary.csv`` one row per cell
and engine, with the machine's load average at the start and at the end (the ratio is paired, the
absolute figures are those of the machine as loaded).
"""
import argparse
import csv
import json
import math
import os
import re
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
RUNNERS = {"yade": os.path.join(ROOT, "yade_scripts", "run_stage.py"),
           "lammps": os.path.join(ROOT, "lammps_scripts", "run_stage.py")}
STATE = {"yade": ".final.yade.gz", "lammps": ".final.lammps"}
#: cell -> geometry, the pre-shear's strain (about 2-3 s of YADE's CPU each), loose packing or not
CELLS = {"quick": dict(geometry={"H_over_d": 37, "W_over_H": 0.5}, strain=0.3, loose=False),
         "paper": dict(geometry={"H_over_d": 37, "W_over_H": 4}, strain=0.04, loose=True),
         "tiny": dict(geometry={"H_over_d": 8, "W_over_H": 4}, strain=0.05, loose=False)}  # 211 disks: the tests'

INERTIAL_NUMBER = 5e-3
SECTIONS = ("Pair", "Neigh", "Comm", "Output", "Modify", "Other")
RUN_COLUMNS = ["cell", "engine", "kind", "ranks", "pair", "first", "disks", "steps", "cpu_s", "wall_s",
               "stage_cpu_s", "sampler_cpu_s", "particle_steps_per_cpu_s", "particle_steps_per_stage_cpu_s",
               "ratio_to_yade", *[f"{s.lower()}_share" for s in SECTIONS]]


def scene_for(cell, engine, sampling=None):
    """yade_scripts/examples/tiny.json with the cell's geometry, the benchmark's rate and strain, the
    preset's sampling (``sampling``), no checkpoint and ``engine``."""
    with open(os.path.join(ROOT, "yade_scripts", "examples", "tiny.json")) as f:
        sc = json.load(f)
    c = CELLS[cell]
    sc["geometry"] = dict(c["geometry"])
    sc["loading"]["inertial_number"] = INERTIAL_NUMBER
    sc["preshear"]["strain"] = c["strain"]
    sc["sampling"].update(sampling or {})
    sc["run"].update(checkpoint_every_s=1e5, progress_every_s=30)
    sc["guards"]["pressure_window_strain"] = max(sc["guards"]["pressure_window_strain"], 2 * c["strain"])
    sc["pack"].update(initial_solid_fraction=0.55, ke_max=1e-6)
    if c["loose"]:  # the big cell packs within minutes (tools/benchmark.py's criteria)
        sc["pack"].update(initial_solid_fraction=0.5, compaction_pressure=0.2, ramp_time=5, ke_max=1e-4,
                          wall_speed_max=1e-2, pressure_tolerance=0.05)
    if engine == "lammps":
        sc["engine"] = "lammps"
    return sc


def child(argv, log, env=None):
    """Run argv; (wall s, CPU s of it and its descendants, stdout). Exits on failure."""
    env = dict(os.environ, OMP_NUM_THREADS="1", **(env or {}))
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    r = subprocess.run(argv, capture_output=True, text=True, env=env, cwd=ROOT)
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    log.write(f"$ {' '.join(argv)}\n{r.stdout}{r.stderr}")
    log.flush()
    if r.returncode != 0:
        sys.exit(f"{' '.join(argv)} failed ({r.returncode}):\n{r.stdout[-2000:]}\n{r.stderr[-2000:]}")
    return dict(wall=wall, cpu=(r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime), stdout=r.stdout)


def stage(engine, scene_path, case, stage_name, log):
    """One stage run; the child's times and the stage's sidecar."""
    res = child(["python3", RUNNERS[engine], scene_path, stage_name, case], log)
    with open(os.path.join(case, f"{stage_name}.json")) as f:
        res["side"] = json.load(f)
    return res


def fresh_case(pack_dir, case):
    """A case folder holding (links to) the packing of ``pack_dir`` only."""
    shutil.rmtree(case, ignore_errors=True)
    os.makedirs(case)
    for name in os.listdir(pack_dir):
        if name.startswith("pack."):
            os.link(os.path.join(pack_dir, name), os.path.join(case, name))
    return case


class Commands:
    """Collects the commands lammps_scripts/cell.py gives a LAMMPS instance, as an input script."""

    def __init__(self):
        self.lines = []

    def command(self, line):
        self.lines.append(line)


def bare_input(scene_path, pack_dir, steps):
    """The input script of a bare LAMMPS pre-shear: the stage's settings (lammps_scripts/cell.py: the
    session's header, the packing's restart file, the contact law, neighbour lists, time step, fixes,
    wall speeds) and one `run` of ``steps`` with LAMMPS's timer table (post yes)."""
    sys.path[:0] = [os.path.join(ROOT, "lammps_scripts"), os.path.join(ROOT, "yade_scripts")]
    try:
        import cell
        import scene as scenemod
    finally:
        del sys.path[:2]
    sc, _ = scenemod.load(scene_path, "preshear")
    der = scenemod.derived(sc)
    with open(os.path.join(pack_dir, "pack.json")) as f:
        lay = json.load(f)["engine_state"]["layout"]
    lmp = Commands()
    cell.load_state(lmp, os.path.join(pack_dir, "pack.final.lammps"))
    cell.interactions(lmp, sc, der)
    cell.fixes(lmp, lay["n_wall"], der["p"] * der["W"] * der["d"])
    cell.set_wall_speeds(lmp, der["U"], -der["U"])
    lmp.command(f"run {steps} post yes")
    return "\n".join(lmp.lines) + "\n"


def parse_lammps_log(text):
    """LAMMPS's loop time, steps and timer shares (percent of the loop) from its log."""
    m = re.search(r"Loop time of ([0-9.eE+-]+) on (\d+) procs for (\d+) steps with (\d+) atoms", text)
    if not m:
        raise ValueError("no `Loop time` line in LAMMPS's log")
    out = dict(loop_s=float(m.group(1)), procs=int(m.group(2)), steps=int(m.group(3)))
    for s in SECTIONS:
        row = re.search(rf"^{s}\s*\|.*\|\s*([0-9.]+)\s*$", text, re.M)
        out[f"{s.lower()}_share"] = float(row.group(1)) / 100 if row else math.nan
    return out


def mpi_launcher(ranks):
    """The command prefix of a LAMMPS run on ``ranks`` MPI ranks: OpenMPI's ranks yield the core
    while they wait for each other (else they spin, and a rank waiting for one the kernel put aside
    burns CPU that is no work); root needs OpenMPI's consent."""
    if ranks == 1 and shutil.which("mpirun") is None:
        return []
    return ["mpirun", "-np", str(ranks), "--mca", "mpi_yield_when_idle", "1",
            *(["--allow-run-as-root"] if os.geteuid() == 0 else [])]


def bare(scene_path, pack_dir, steps, ranks, work, log):
    """A bare LAMMPS pre-shear on ``ranks`` ranks: its times and timer shares."""
    folder = os.path.join(work, f"bare_{ranks}")
    os.makedirs(folder, exist_ok=True)
    script = os.path.join(folder, "in.preshear")
    with open(script, "w") as f:
        f.write(bare_input(scene_path, pack_dir, steps))
    lmp_log = os.path.join(folder, "log.lammps")
    res = child([*mpi_launcher(ranks), "lmp", "-in", script, "-log", lmp_log, "-screen", "none", "-nocite"], log)
    with open(lmp_log) as f:
        res.update(parse_lammps_log(f.read()))
    return res


def busy_cores(window=2.0):
    """Cores busy now: the non-idle share of all CPU time over ``window`` seconds (/proc/stat's
    ``cpu`` line; idle = idle + iowait), times the cores; the 1-minute load average where
    /proc/stat is absent. Read while this benchmark waits, so its own runs just before (which
    the lagging load average still counts for a minute) are not taken for other jobs."""
    def times():
        with open("/proc/stat") as f:
            v = [int(x) for x in f.readline().split()[1:]]
        return sum(v), v[3] + v[4]
    try:
        total0, idle0 = times()
        time.sleep(window)
        total1, idle1 = times()
    except (OSError, ValueError, IndexError):
        return os.getloadavg()[0]
    cores = os.cpu_count() or 1
    return cores * (1.0 - (idle1 - idle0) / max(total1 - total0, 1))


def ranks_to_run(asked, busy=None):
    """The asked rank counts this machine can run honestly, and why the others are left out: more
    than one rank needs mpirun, that many cores, and that many cores free (cores busy now,
    ``busy_cores``, at most cores - ranks + 0.5): on busy cores the ranks mostly wait for each
    other, and the figure would measure the other jobs, not LAMMPS."""
    cores = os.cpu_count() or 1
    run, skipped = [], []
    for r in asked:
        if r == 1:
            run.append(r)
        elif shutil.which("mpirun") is None:
            skipped.append(f"{r} ranks: no mpirun")
        elif r > cores:
            skipped.append(f"{r} ranks: {cores} cores")
        else:
            busy = busy_cores() if busy is None else busy
            if busy > cores - r + 0.5:
                skipped.append(f"{r} ranks: {busy:.2f} of {cores} cores busy leaves fewer than {r} free")
            else:
                run.append(r)
    return run, skipped


def write_csv(path, rows, columns=None):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=columns or list(rows[0]), extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)


def sibling(out, suffix):
    root, ext = os.path.splitext(out)
    return f"{root}_{suffix}{ext}"


def run_cell(cell, args, work, log):
    """Pack with each engine, the paired pre-shears, the bare LAMMPS runs: the cell's rows."""
    rows, paths, packs = [], {}, {}
    for engine in ("yade", "lammps"):
        paths[engine] = os.path.join(work, f"scene_{engine}.json")
        with open(paths[engine], "w") as f:
            json.dump(scene_for(cell, engine, args.sampling), f)
        packs[engine] = os.path.join(work, engine, "pack")
        r = stage(engine, paths[engine], packs[engine], "pack", log)
        print(f"[{cell}] {engine} packed {r['side']['N']} disks in {r['cpu']:.1f} s of CPU", flush=True)
    for k in range(args.pairs):
        order = ("yade", "lammps") if k % 2 == 0 else ("lammps", "yade")
        got = {}
        for engine in order:
            case = fresh_case(packs[engine], os.path.join(work, engine, "case"))
            r = stage(engine, paths[engine], case, "preshear", log)
            s = r["side"]
            got[engine] = dict(cell=cell, engine=engine, kind="stage", ranks=1, pair=k + 1, first=order[0],
                               disks=s["N"], steps=s["steps"], cpu_s=r["cpu"], wall_s=r["wall"],
                               stage_cpu_s=s["cpu_time_s"], sampler_cpu_s=s["sampler_cpu_s"],
                               particle_steps_per_cpu_s=s["N"] * s["steps"] / r["cpu"],
                               particle_steps_per_stage_cpu_s=s["N"] * s["steps"] / s["cpu_time_s"])
        ratio = got["lammps"]["particle_steps_per_stage_cpu_s"] / got["yade"]["particle_steps_per_stage_cpu_s"]
        got["lammps"]["ratio_to_yade"] = ratio
        rows += [got["yade"], got["lammps"]]
        args.keep(rows)
        print(f"[{cell}] pair {k + 1} ({order[0]} first): particle-steps per stage CPU s YADE "
              f"{got['yade']['particle_steps_per_stage_cpu_s']:.3g} ({got['yade']['disks']} disks), LAMMPS "
              f"{got['lammps']['particle_steps_per_stage_cpu_s']:.3g} ({got['lammps']['disks']} disks): "
              f"{ratio:.2f}x", flush=True)
    steps = rows[-1]["steps"] if rows else 0
    ranks_run, skipped = ranks_to_run(args.ranks)
    for why in skipped:
        print(f"[{cell}] bare LAMMPS not run on {why}", flush=True)
    for ranks in ranks_run:
        b = bare(paths["lammps"], packs["lammps"], steps, ranks, os.path.join(work, "lammps"), log)
        disks = rows[-1]["disks"]
        row = dict(cell=cell, engine="lammps", kind="bare", ranks=ranks, disks=disks, steps=b["steps"],
                   cpu_s=b["cpu"], wall_s=b["wall"], particle_steps_per_cpu_s=disks * b["steps"] / b["cpu"],
                   **{k: v for k, v in b.items() if k.endswith("_share")})
        rows.append(row)
        args.keep(rows)
        print(f"[{cell}] bare LAMMPS on {ranks} rank(s): {row['particle_steps_per_cpu_s']:.3g} particle-steps per "
              f"CPU s (loop {b['loop_s']:.2f} s wall, {b['cpu']:.2f} s CPU); "
              + ", ".join(f"{s} {100 * b[f'{s.lower()}_share']:.0f}%" for s in SECTIONS), flush=True)
    return rows


def summary(rows, load):
    """Per cell, engine, kind and ranks: the median particle-steps per CPU second; LAMMPS's stages their
    paired ratio to YADE's (median, min, max); the load averages."""
    out = []
    keys = sorted({(r["cell"], r["engine"], r["kind"], r["ranks"]) for r in rows})
    for cell, engine, kind, ranks in keys:
        rs = [r for r in rows if (r["cell"], r["engine"], r["kind"], r["ranks"]) == (cell, engine, kind, ranks)]
        key = "particle_steps_per_stage_cpu_s" if kind == "stage" else "particle_steps_per_cpu_s"
        ratios = [r["ratio_to_yade"] for r in rs if r.get("ratio_to_yade")]
        out.append(dict(cell=cell, engine=engine, kind=kind, ranks=ranks, disks=rs[0]["disks"], runs=len(rs),
                        particle_steps_per_cpu_s=statistics.median(r[key] for r in rs),
                        ratio_median=statistics.median(ratios) if ratios else "",
                        ratio_min=min(ratios) if ratios else "", ratio_max=max(ratios) if ratios else "",
                        sampler_share=(statistics.median(r["sampler_cpu_s"] / r["stage_cpu_s"] for r in rs)
                                       if kind == "stage" else ""),
                        loadavg_start=load[0], loadavg_end=load[1], cores=os.cpu_count()))
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=os.path.join("results", "accuracy", "engine_throughput.csv"))
    ap.add_argument("--cells", default="quick,paper", help=f"comma-separated, of {', '.join(CELLS)}")
    ap.add_argument("--pairs", type=int, default=2)
    ap.add_argument("--ranks", default="1,2", help="MPI ranks of the bare LAMMPS runs (those the machine has)")
    ap.add_argument("--strain", type=float, help="the pre-shear's strain in every cell (default: the cell's, CELLS)")
    ap.add_argument("--sampling", type=json.loads, default=None, help="JSON: the scene's sampling section")
    ap.add_argument("--work", help="folder of the runs, kept (default: a temporary folder, removed)")
    args = ap.parse_args(argv)
    args.ranks = [int(x) for x in args.ranks.split(",")]
    if args.strain is not None:
        for c in CELLS.values():
            c["strain"] = args.strain
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    work = args.work or tempfile.mkdtemp(prefix="engine_bench_")
    os.makedirs(work, exist_ok=True)
    load0 = os.getloadavg()[0]
    print(f"load average (1 min) {load0:.2f} on {os.cpu_count()} cores", flush=True)
    rows = []
    # every run's row on disk as soon as it is measured: an interrupted benchmark keeps what it measured
    args.keep = lambda cell_rows: write_csv(args.out, rows + cell_rows, RUN_COLUMNS)
    with open(os.path.join(work, "children.log"), "w") as log:
        try:
            for cell in args.cells.split(","):
                folder = os.path.join(work, cell)
                os.makedirs(folder, exist_ok=True)
                rows += run_cell(cell, args, folder, log)
        finally:
            if not args.work:
                shutil.rmtree(work, ignore_errors=True)
    load1 = os.getloadavg()[0]
    write_csv(args.out, rows, RUN_COLUMNS)
    summ = summary(rows, (load0, load1))
    write_csv(sibling(args.out, "summary"), summ)
    for s in summ:
        print(f"{s['cell']:>6} {s['engine']:>6} {s['kind']:>5} ranks {s['ranks']}: {s['disks']} disks, "
              f"{s['particle_steps_per_cpu_s']:.3g} particle-steps per CPU s"
              + (f", {s['ratio_median']:.2f}x YADE's (paired, {s['ratio_min']:.2f}-{s['ratio_max']:.2f})"
                 if s["ratio_median"] != "" else ""), flush=True)
    print(f"load average (1 min) {load0:.2f} at the start, {load1:.2f} at the end, {os.cpu_count()} cores; "
          f"wrote {args.out}", flush=True)


if __name__ == "__main__":
    main()
