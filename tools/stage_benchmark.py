"""Does the project's DEM stage cost more than YADE itself? The stage against bare YADE, paired.

    python3 tools/stage_benchmark.py [--out results/accuracy/stage_overhead.csv] [--pairs 4]
        [--h-over-d 10] [--strain 1.5] [--inertial-number 2e-3] [--sampling JSON] [--run JSON]

(standard library only; the children import YADE as a library, on one thread.) From one
packing (the pack stage of a small cell made from yade_scripts/examples/tiny.json, W = 4H),
P pairs of runs of the same pre-shear, in the order A, B, then B, A, alternately:

- A, the stage: ``python3 yade_scripts/run_stage.py <scene> preshear <case>`` (the sampler
  with the fabric and stress, the CSV, the guards, progress lines, a self-reload every
  checkpoint.RELOAD_EVERY steps, run chunks of about stages.CHUNK_S of wall time,
  checkpoints every run.checkpoint_every_s);
- B, bare YADE (``bare``, this script's other command, under the same interpreter): the same
  start (pack.final.yade.gz, the stage's dt, wall load and wall speeds set by build.py) and
  the same engines (engines.build, the sampler PyRunner left out), one ``O.run(n, True)`` of
  the stage's n = ceil(strain / (gammadot dt)) steps, the final state saved.

Per run: wall time (time.perf_counter around the child process), CPU time (user + sys of
the child, getrusage RUSAGE_CHILDREN) and its context switches. Per pair k:

.. math:: r_{cpu,k} = \\frac{CPU_{A,k}}{CPU_{B,k}}, \\qquad r_{wall,k} = \\frac{wall_{A,k}}{wall_{B,k}}

Printed and written (``--out``, one row per pair): the ratios, and whether the two final
states are the same to the bit (positions, velocities, orientations, angular velocities;
expected only for n < RELOAD_EVERY: a reload reorders the contacts, see checkpoint.py);
the summary (``<out>_summary.csv``): median, min and max of r_cpu and r_wall over the pairs.

Where the stage's wall time goes (``<out>_wall.csv``): one more stage run in this process's
child with timers around each part (``profile``: the engines' own times with
O.timingEnabled, the rest of each O.run(n, True), the reloads, checkpoints, lock and log
touches, the start and the finish), and one timed bare run, each part as seconds of wall and
of CPU (time.process_time) and its share of the run's wall time.

The cost of a run chunk alone: ``bare <scene> <case> <out.json> --timing --chunks K [--wait
fine]`` runs the same steps as K calls of O.run (YADE's wait, which sleeps 40 ms between
looks, or a sleep through 90 % of the predicted time, then a look every millisecond) and
writes the engines' time and the rest of O.run.
"""
import argparse
import csv
import json
import math
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
YS = os.path.join(ROOT, "yade_scripts")
RUN = os.path.join(YS, "run_stage.py")
SELF = os.path.abspath(__file__)
PAIR_COLUMNS = ["pair", "first", "steps", "cpu_stage_s", "cpu_bare_s", "wall_stage_s", "wall_bare_s",
                "cpu_ratio", "wall_ratio", "nvcsw_stage", "nvcsw_bare", "nivcsw_stage", "nivcsw_bare",
                "same_final_state"]


# --- the orchestrator (no YADE) ----------------------------------------------------------------

def scene_for(h_over_d, strain, inertial_number, sampling=None, run=None):
    """tiny.json with H = h_over_d d (W = 4H), the pre-shear's strain and rate, and the
    sampling and run sections updated from ``sampling`` and ``run`` (a preset's)."""
    with open(os.path.join(YS, "examples", "tiny.json")) as f:
        sc = json.load(f)
    sc["geometry"] = {"H_over_d": h_over_d, "W_over_H": 4}
    sc["loading"]["inertial_number"] = inertial_number
    sc["pack"].update(initial_solid_fraction=0.55, ke_max=1e-6)  # a packing in seconds
    sc["preshear"]["strain"] = strain
    sc["sampling"].update(sampling or {})
    sc["run"].update(run or {})
    sc["guards"]["pressure_window_strain"] = max(sc["guards"]["pressure_window_strain"], strain)
    return sc


def child(argv, log):
    """Run argv on one thread; (wall s, CPU s, voluntary and involuntary context switches)."""
    env = dict(os.environ, OMP_NUM_THREADS="1")
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    r = subprocess.run(argv, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    if log is not None:
        log.write(f"$ {' '.join(argv)}\n{r.stdout}{r.stderr}")
        log.flush()
    if r.returncode != 0:
        sys.exit(f"{' '.join(argv)} failed ({r.returncode}):\n{r.stdout[-2000:]}\n{r.stderr[-2000:]}")
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    return dict(wall=wall, cpu=cpu, nvcsw=r1.ru_nvcsw - r0.ru_nvcsw, nivcsw=r1.ru_nivcsw - r0.ru_nivcsw,
                stdout=r.stdout)


def fresh_case(work, name):
    """A case folder holding (a link to) the packing only."""
    case = os.path.join(work, name)
    shutil.rmtree(case, ignore_errors=True)
    os.makedirs(case)
    os.link(os.path.join(work, "pack", "pack.final.yade.gz"), os.path.join(case, "pack.final.yade.gz"))
    return case


def run_stage(scene_path, case, log):
    res = child(["python3", RUN, scene_path, "preshear", case], log)
    with open(os.path.join(case, "preshear.json")) as f:
        res["steps"] = json.load(f)["steps"]
    res["final"] = os.path.join(case, "preshear.final.yade.gz")
    return res


def run_bare(scene_path, case, log, timing=False):
    out = os.path.join(case, "bare.json")
    res = child(["python3", SELF, "bare", scene_path, case, out] + (["--timing"] if timing else []), log)
    with open(out) as f:
        res.update(json.load(f))
    return res


def same_state(a, b, log):
    """Whether the saved states a and b hold the same bodies' states to the bit (read by YADE)."""
    r = child(["python3", SELF, "digest", a, b], log)
    digests = [line.split()[1] for line in r["stdout"].splitlines() if line.startswith("DIGEST ")]
    return len(digests) == 2 and digests[0] == digests[1]


def summary(pairs):
    rows = []
    for name in ("cpu_ratio", "wall_ratio"):
        xs = [p[name] for p in pairs]
        rows.append(dict(quantity=name, pairs=len(xs), median=statistics.median(xs), min=min(xs), max=max(xs)))
    return rows


def write_csv(path, rows, columns=None):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=columns or list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def sibling(out, suffix):
    root, ext = os.path.splitext(out)
    return f"{root}_{suffix}{ext}"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=os.path.join("results", "accuracy", "stage_overhead.csv"))
    ap.add_argument("--pairs", type=int, default=4)
    ap.add_argument("--h-over-d", type=float, default=10)
    ap.add_argument("--strain", type=float, default=1.5, help="of the pre-shear: sets the number of steps")
    ap.add_argument("--inertial-number", type=float, default=2e-3)
    ap.add_argument("--sampling", type=json.loads, default=None, help="JSON: the scene's sampling section")
    ap.add_argument("--run", type=json.loads, default=None, help="JSON: the scene's run section")
    ap.add_argument("--no-profile", action="store_true", help="skip the wall-time breakdown")
    ap.add_argument("--work", help="folder of the runs, kept (default: a temporary folder, removed)")
    args = ap.parse_args(argv)
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    work = args.work or tempfile.mkdtemp(prefix="stage_bench_")
    os.makedirs(work, exist_ok=True)
    log = open(os.path.join(work, "children.log"), "w")
    try:
        scene_path = os.path.join(work, "scene.json")
        with open(scene_path, "w") as f:
            json.dump(scene_for(args.h_over_d, args.strain, args.inertial_number, args.sampling, args.run), f)
        child(["python3", RUN, scene_path, "pack", os.path.join(work, "pack")], log)
        with open(os.path.join(work, "pack", "pack.json")) as f:
            n_disks = json.load(f)["N"]
        pairs = []
        for k in range(args.pairs):
            first = "stage" if k % 2 == 0 else "bare"
            got = {}
            for side in ([first, "bare" if first == "stage" else "stage"]):
                case = fresh_case(work, side)
                got[side] = run_stage(scene_path, case, log) if side == "stage" else run_bare(scene_path, case, log)
            a, b = got["stage"], got["bare"]
            if a["steps"] != b["steps"]:
                sys.exit(f"pair {k + 1}: the stage ran {a['steps']} steps, bare YADE {b['steps']}")
            row = dict(pair=k + 1, first=first, steps=a["steps"], cpu_stage_s=a["cpu"], cpu_bare_s=b["cpu"],
                       wall_stage_s=a["wall"], wall_bare_s=b["wall"], cpu_ratio=a["cpu"] / b["cpu"],
                       wall_ratio=a["wall"] / b["wall"], nvcsw_stage=a["nvcsw"], nvcsw_bare=b["nvcsw"],
                       nivcsw_stage=a["nivcsw"], nivcsw_bare=b["nivcsw"],
                       same_final_state=same_state(a["final"], b["final"], log))
            pairs.append(row)
            print(f"pair {k + 1} ({first} first, N = {n_disks}, {row['steps']} steps): CPU {a['cpu']:.2f} / "
                  f"{b['cpu']:.2f} s = {row['cpu_ratio']:.3f}, wall {a['wall']:.2f} / {b['wall']:.2f} s = "
                  f"{row['wall_ratio']:.3f}, context switches voluntary {a['nvcsw']} / {b['nvcsw']}, "
                  f"involuntary {a['nivcsw']} / {b['nivcsw']}, same final state: {row['same_final_state']}",
                  flush=True)
        write_csv(args.out, pairs, PAIR_COLUMNS)
        summ = summary(pairs)
        write_csv(sibling(args.out, "summary"), summ)
        for s in summ:
            print(f"{s['quantity']} (stage / bare YADE, {s['pairs']} pairs): median {s['median']:.3f}, "
                  f"min {s['min']:.3f}, max {s['max']:.3f}", flush=True)
        if not args.no_profile:
            rows = profile_rows(scene_path, work, log)
            write_csv(sibling(args.out, "wall"), rows)
            for r in rows:
                print(f"wall time of the {r['run']}: {r['part']:<34} wall {r['wall_s']:8.3f} s  "
                      f"CPU {r['cpu_s']:8.3f} s  {100 * r['wall_share']:5.1f}% of the run's wall"
                      + (f"  ({r['count']} times)" if r["count"] else ""), flush=True)
        print(f"wrote {args.out}")
    finally:
        log.close()
        if not args.work:
            shutil.rmtree(work, ignore_errors=True)


def profile_rows(scene_path, work, log):
    """The wall-time breakdown: one instrumented stage run, one timed bare run."""
    case = fresh_case(work, "stage")
    out = os.path.join(work, "profile.json")
    r = child(["python3", SELF, "profile", scene_path, case, out], log)
    with open(out) as f:
        prof = json.load(f)
    rows = [dict(run="stage", part=k, wall_s=v["wall"], cpu_s=v["cpu"], count=v.get("count", 0),
                 wall_share=v["wall"] / r["wall"]) for k, v in prof["parts"].items()]
    rows.append(dict(run="stage", part="the whole process", wall_s=r["wall"], cpu_s=r["cpu"], count=0, wall_share=1.0))
    b = run_bare(scene_path, fresh_case(work, "bare"), log, timing=True)
    rows += [dict(run="bare", part=k, wall_s=v["wall"], cpu_s=v["cpu"], count=v.get("count", 0),
                  wall_share=v["wall"] / b["wall"]) for k, v in b["parts"].items()]
    rows.append(dict(run="bare", part="the whole process", wall_s=b["wall"], cpu_s=b["cpu"], count=0, wall_share=1.0))
    return rows


# --- the children (YADE as a library) ----------------------------------------------------------

def _import_yade():
    sys.path.insert(0, YS)
    import yadelib

    yadelib.run_under_yade_interpreter()  # YADE's own interpreter: no remote servers (docs/scene.md)
    yadelib.import_yade()


class Parts:
    """Wall (perf_counter) and CPU (process_time) seconds and call counts, per named part."""

    def __init__(self):
        self.parts = {}

    def add(self, name, wall, cpu):
        p = self.parts.setdefault(name, dict(wall=0.0, cpu=0.0, count=0))
        p["wall"] += wall
        p["cpu"] += cpu
        p["count"] += 1

    def timed(self, name, fn):
        def wrapper(*a, **kw):
            w0, c0 = time.perf_counter(), time.process_time()
            try:
                return fn(*a, **kw)
            finally:
                self.add(name, time.perf_counter() - w0, time.process_time() - c0)
        return wrapper


def engine_seconds(O, pyrunners):
    """Cumulative execTime (O.timingEnabled) of the engines that are (not) PyRunners, in s."""
    from yade.wrapper import PyRunner

    return 1e-9 * sum(e.execTime for e in O.engines if isinstance(e, PyRunner) == pyrunners)


def run_and_wait(O, n, how, rate={}):
    """O.run(n, True) (how = "yade": YADE's wait, which sleeps 40 ms between looks), or the
    stage's wait, ``runwait.run_and_wait`` (how = "fine": a sleep through 90 % of the time the
    last chunk's rate predicts, then a look at O.running every millisecond)."""
    if how == "yade":
        O.run(n, True)
        return
    import runwait   # the stage's own wait (yade_scripts/runwait.py)

    rate["steps_per_s"] = runwait.run_and_wait(O, n, rate.get("steps_per_s"))


def untimed_run(O, parts, how="yade"):
    def run(n, wait=True):
        w0, c0 = time.perf_counter(), time.process_time()
        run_and_wait(O, n, how)
        parts.add("O.run: all", time.perf_counter() - w0, time.process_time() - c0)
    return run


def timed_run(O, parts, how="yade"):
    """O.run(n, True), its wall and CPU split into the engines' own time (physics, Python
    runners) and the rest (thread start, the loop, the wait for the end)."""
    def run(n, wait=True):
        e0, p0 = engine_seconds(O, False), engine_seconds(O, True)
        w0, c0 = time.perf_counter(), time.process_time()
        run_and_wait(O, n, how)
        wall, cpu = time.perf_counter() - w0, time.process_time() - c0
        eng, py = engine_seconds(O, False) - e0, engine_seconds(O, True) - p0
        parts.add("O.run: engines (physics)", eng, 0.0)
        parts.add("O.run: PyRunners (sampler)", py, 0.0)
        parts.add("O.run: outside the engines", wall - eng - py, 0.0)
        parts.add("O.run: all", wall, cpu)
    return run


def bare(argv):
    """One bare run: the stage's start and engines without the sampler, one O.run(n, True)."""
    ap = argparse.ArgumentParser(prog="stage_benchmark.py bare")
    ap.add_argument("scene")
    ap.add_argument("case")
    ap.add_argument("out")
    ap.add_argument("--timing", action="store_true")
    ap.add_argument("--chunks", type=int, default=1, help="the n steps as this many equal O.run calls")
    ap.add_argument("--wait", choices=["yade", "fine"], default="yade",
                    help="yade: O.run(k, True), whose wait polls every 40 ms; fine: O.run(k), a sleep through "
                         "90%% of the predicted time, then a look at O.running every ms")
    args = ap.parse_args(argv)
    _import_yade()
    parts = Parts()
    w0, c0 = time.perf_counter(), time.process_time()
    import build
    import engines
    import scene as scenemod
    from yade.wrapper import Omega

    O = Omega()
    sc, _ = scenemod.load(args.scene, "preshear")
    der = scenemod.derived(sc)
    O.load(os.path.join(args.case, "pack.final.yade.gz"))
    lay = build.layout()
    dt = json.loads(O.tags["ys_state"])["dt"]
    build.set_wall_speeds(lay, der["U"], -der["U"])
    O.dt = dt
    build.set_wall_load(lay, der["p"] * der["W"] * der["d"])
    O.engines = [e for e in engines.build(sc, 1, "pass") if e.label != "sampler"]
    n = int(math.ceil(sc["preshear"]["strain"] / (der["gammadot"] * der["dt"])))  # as shearing.py counts
    parts.add("start (imports, load, engines)", time.perf_counter() - w0, time.process_time() - c0)
    i0 = O.iter
    O.timingEnabled = args.timing
    run = timed_run(O, parts, args.wait) if args.timing else untimed_run(O, parts, args.wait)
    for k in range(args.chunks):
        run(n * (k + 1) // args.chunks - n * k // args.chunks, True)
    steps = O.iter - i0
    w0, c0 = time.perf_counter(), time.process_time()
    O.save(os.path.join(args.case, "bare.final.yade.gz"))
    parts.add("finish (save the final state)", time.perf_counter() - w0, time.process_time() - c0)
    with open(args.out, "w") as f:
        json.dump(dict(steps=steps, final=os.path.join(args.case, "bare.final.yade.gz"), parts=parts.parts), f)
    return 0


def profile(argv):
    """One stage run (run_stage.main in this process) with timers around its parts."""
    scene_path, case, out = argv
    _import_yade()
    import run_stage
    import stagecli
    import stages
    from yade.wrapper import Omega

    O = Omega()
    O.timingEnabled = True
    parts = Parts()

    class TimedOmega:  # stages.py's O: its O.run timed, everything else passed through
        def __getattr__(self, name):
            return getattr(O, name)

        def __setattr__(self, name, value):
            setattr(O, name, value)

    timed = TimedOmega()
    object.__setattr__(timed, "run", timed_run(O, parts))
    stages.O = timed
    S = stages.Stage
    for name, part in [("prepare", "start (load, first reload, engines)"),
                       ("reload", "reloads (every RELOAD_EVERY steps)"), ("checkpoint", "checkpoints"),
                       ("finish", "finish (final state, CSV, sidecar)"), ("progress", "progress lines")]:
        setattr(S, name, parts.timed(part, getattr(S, name)))
    stagecli.Renew.touch = parts.timed("lock and log touch", stagecli.Renew.touch)
    w0, c0 = time.perf_counter(), time.process_time()
    rc = run_stage.main([scene_path, "preshear", case])
    parts.add("run_stage.main: all", time.perf_counter() - w0, time.process_time() - c0)
    with open(out, "w") as f:
        json.dump(dict(rc=rc, parts=parts.parts), f)
    return rc


def digest(paths):
    """Print DIGEST <sha256> of each saved state's bodies (pos, vel, ori, angVel as exact hex)."""
    import hashlib

    _import_yade()
    from yade.wrapper import Omega

    O = Omega()
    for path in paths:
        O.load(path)
        h = hashlib.sha256()
        for b in O.bodies:
            s = b.state
            vals = list(s.pos) + list(s.vel) + list(s.angVel) + [s.ori.toAxisAngle()[1]] + list(s.ori.toAxisAngle()[0])
            h.update(",".join(float(v).hex() for v in vals).encode())
        h.update(repr(O.iter).encode())
        print(f"DIGEST {h.hexdigest()} {path}", flush=True)
    return 0


if __name__ == "__main__":
    commands = dict(bare=bare, profile=profile, digest=digest)
    if len(sys.argv) > 1 and sys.argv[1] in commands:
        rc = commands[sys.argv[1]](sys.argv[2:])
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(rc)  # YADE's threads are not joined at exit (as run_stage.py)
    main()
