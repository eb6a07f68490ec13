"""Helpers shared by the test modules: real YADE on tiny scenes, Snakemake in a private working copy.

Plain functions (no fixtures: those are in conftest.py), imported as ``from tests.helpers import ...``
so that no test module imports another.

Isolation. Every Snakemake call runs in a working copy of the workflow (``workflow_copy``): a
folder of symbolic links to the repository's code, so its ``.snakemake/`` (locks, metadata,
incomplete markers) and its default ``results/`` are its own, and two pytest-xdist workers never
share them. A module from ``yade_scripts/`` is loaded under a private name (``yade_module``)
without putting that folder on ``sys.path`` for the whole run.
"""
import contextlib
import importlib
import importlib.util
import io
import json
import os
import signal
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

from claims.inputs import read_dem_case
from claims.table import claims_table
from compare import comparison
from dem_contract.synthetic import FABRIC_NOISE, MU_NOISE, write_ensemble
from model import default_params, params_from_dict, save_params

ROOT = Path(__file__).resolve().parents[1]
YS = ROOT / "yade_scripts"
RUN = YS / "run_stage.py"
LS = ROOT / "lammps_scripts"
LAMMPS_RUN = LS / "run_stage.py"
SNAKEMAKE = [sys.executable, "-m", "snakemake"]

# What a working copy leaves out: the repository's own results and Snakemake state, and the tests.
NOT_COPIED = {".git", ".snakemake", ".pytest_cache", "__pycache__", "tests", "logs", "benchmarks"}


# --- YADE ----------------------------------------------------------------------------------

def command(script, *args):
    """The command line of a script: the stage runner and the tools/ scripts as the workflow runs
    them (python3, YADE imported as a library, no remote servers), any other script (an
    inspection written by a test) under the yade launcher."""
    if Path(script).name in ("run_stage.py", "contact_census.py") or Path(script).parent.name in ("tools", "lammps_scripts"):
        return ["python3", str(script), *map(str, args)]
    return ["yade", "-n", "-x", str(script), *map(str, args)]


def yade(script, *args, cwd=None, timeout=600):
    """Run ``script`` (``command``) on one thread; the CompletedProcess (text output)."""
    env = dict(os.environ, OMP_NUM_THREADS="1")
    return subprocess.run(command(script, *args), capture_output=True, text=True,
                          cwd=cwd, timeout=timeout, env=env)


def yade_module(name):
    """The pure-Python module ``yade_scripts/<name>.py``, loaded as ``yade_scripts_<name>``.

    ``sys.path`` is left as it was (the folder's ``scene``, ``stages``... would otherwise shadow
    other modules of that name for every later test of the worker)."""
    spec = importlib.util.spec_from_file_location(f"yade_scripts_{name}", YS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def make_scene(example="tiny.json"):
    """A tiny example scene of yade_scripts/examples/ with short stages (a few seconds each)."""
    sc = json.loads((YS / "examples" / example).read_text())
    # the pack's defaults, but a lower compaction friction, so that its restore is tested
    sc["pack"].update(initial_solid_fraction=0.55, ke_max=1e-6, friction=0.2)
    sc["preshear"]["strain"] = 1.2
    sc["heaviside"]["strain"] = 0.4
    sc["sinusoidal"].update(strain=0.3, transition_strain=0.1)
    sc["run"].update(checkpoint_every_s=1000, progress_every_s=5)
    return sc


def read(path):
    return np.genfromtxt(path, delimiter=",", names=True)


def run_all_stages(root, sc):
    """Write the scene ``sc`` under ``root`` and run pack, preshear, heaviside, sinusoidal in ``root/case``."""
    scene = root / "scene.json"
    scene.write_text(json.dumps(sc))
    cdir = root / "case"
    for stage in ("pack", "preshear", "heaviside", "sinusoidal"):
        r = yade(RUN, scene, stage, cdir)
        assert r.returncode == 0, f"{stage}: {r.stdout[-2000:]}\n{r.stderr[-2000:]}"
    return dict(dir=cdir, scene=scene, root=root)


INSPECT_PACKING = """
import json, sys
from yade.wrapper import NewtonIntegrator, Omega
O = Omega()
O.load(sys.argv[1])
lay = json.loads(O.tags["ys_layout"])
print("PACKING " + json.dumps(dict(
    materials=[float(m.frictionAngle) for m in O.materials],
    contacts=[float(i.phys.tangensOfFrictionAngle) for i in O.interactions if i.isReal],
    damping=[float(e.damping) for e in O.engines if isinstance(e, NewtonIntegrator)],
    wall_damped=[bool(O.bodies[lay["clump"]].state.isDamped)] if "clump" in lay else [])), flush=True)
"""


def saved_packing(tmp_path, state):
    """Friction angles of the materials, friction coefficients of the contacts, the NewtonIntegrator's
    damping and the top wall's State.isDamped in a saved state (read by YADE itself)."""
    script = tmp_path / "inspect_packing.py"
    script.write_text(INSPECT_PACKING)
    r = yade(script, state)
    assert r.returncode == 0, r.stderr[-2000:]
    return json.loads(r.stdout.split("PACKING ", 1)[1].splitlines()[0])


def assert_pack_restored_the_grains_own_friction_and_damping(case, tmp_path):
    """The pack compacts with pack.friction and damps with pack.damping; the saved packing
    has material.friction on every material and contact and effects.damping in the integrator."""
    sc = json.loads(case["scene"].read_text())
    mu, damping = sc["material"]["friction"], sc["effects"]["damping"]
    assert sc["pack"]["friction"] < mu and sc["pack"].get("damping", 0.5) != damping  # else nothing is tested
    got = saved_packing(tmp_path, case["dir"] / "pack.final.yade.gz")
    assert len(got["contacts"]) > 100
    assert np.allclose(np.tan(got["materials"]), mu, rtol=1e-12, atol=0)
    assert np.allclose(got["contacts"], mu, rtol=1e-12, atol=0)
    assert got["damping"] == [damping]
    assert all(got["wall_damped"])


def kill_preshear_after_first_checkpoint(scene, cdir, stage="preshear", ready=None, log=None, runner=RUN):
    """Start the pre-shear (or ``stage``) of ``cdir``, SIGKILL it 0.7 s after its first checkpoint
    (its first for which ``ready(resume.json's dict)`` is true, if given); return its PID. With ``log``,
    the stage writes its log there (run_stage.py --log, as the workflow runs it). ``runner``: the
    engine's run_stage.py (YADE's, or LAMMPS_RUN)."""
    resume = Path(cdir) / ".partial" / stage / "resume.json"
    env = dict(os.environ, OMP_NUM_THREADS="1")
    proc = subprocess.Popen(command(runner, scene, stage, cdir, *(["--log", log] if log else [])),
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)

    def checkpointed():
        if not resume.exists():
            return False
        try:
            return ready is None or ready(json.loads(resume.read_text()))
        except json.JSONDecodeError:
            return False

    try:
        t0 = time.time()
        while not checkpointed():
            assert proc.poll() is None, "the stage ended before its first checkpoint"
            assert time.time() - t0 < 120
            time.sleep(0.1)
        time.sleep(0.7)  # rows past the checkpoint get written, then are lost with the kill
        assert proc.poll() is None, "the stage ended before it could be killed"
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    finally:
        if proc.poll() is None:
            proc.kill()
    return proc.pid


def assert_resumed_without_gap_or_duplicate(cdir):
    """The resumed pre-shear of ``cdir``: flagged resumed, t and strain strictly increasing (no duplicate,
    no reordering), no step between rows longer than the coarse sampling interval (no gap).
    Returns its series and sidecar."""
    side = json.loads((cdir / "preshear.json").read_text())
    assert side["resumed"] == 1
    s = read(cdir / "preshear.csv")
    t, strain = s["t"], s["strain"]
    assert np.all(np.diff(t) > 0) and np.all(np.diff(strain) > 0)  # no duplicate, no reordering
    dt_coarse = side["sampling_steps"]["coarse"] * side["dt"] / side["time_unit_s"]
    assert np.diff(t).max() <= dt_coarse * (1 + 1e-9)  # no gap: not even one step more than the grid
    return s, side


def assert_schedule_reversals(cdir, name, segments):
    """The schedule ``name`` of ``cdir``, run from its pre-shear with ``segments`` (each segment's
    direction differing from the one before it), whichever engine ran it: one series through the
    contract's reader; the sidecar's reversals in order, at the scheduled strains (strain at the
    nominal rate) within one step; the readers find them from the rate alone, within one sampling
    interval (the rate turns at a sharp reversal, half way through a half cosine)."""
    from dem_contract import read_series, split_transients

    side = json.loads((Path(cdir) / f"{name}.json").read_text())
    pre, run = read_series(Path(cdir) / "preshear.csv"), read_series(Path(cdir) / f"{name}.csv")
    directions = [seg["direction"] for seg in segments]
    assert side["samples"] == len(run)
    assert [r["direction"] for r in side["reversals"]] == directions
    assert [r["transition"] for r in side["reversals"]] == [s.get("transition", "heaviside") for s in segments]
    assert (side["reversal_t"], side["reversal_strain"]) == (side["reversals"][0]["t"], side["reversals"][0]["strain"])
    I, step = side["inertial_number"], side["gammadot_nominal"] * side["dt"]
    scheduled = np.cumsum([0.0] + [s["strain"] for s in segments[:-1]])
    assert np.abs((np.array([r["t"] for r in side["reversals"]]) - side["t_start"]) * I - scheduled).max() <= step * 1.001
    fine = make_scene()["sampling"]["fine_interval"]
    found = split_transients(pre, run)
    assert len(found) == len(segments)
    for tr, r in zip(found, side["reversals"]):
        t_turn = r["t"] + 0.5 * r.get("transition_strain", 0.0) / I
        assert abs(tr.t0 - t_turn) * I <= fine * 1.001 + step
        if r["transition"] == "heaviside":
            assert abs(tr.strain0 - r["strain"]) <= 1.1 * fine
    assert [tr.sign for tr in found] == [float(d) for d in directions]
    stated = split_transients(pre, run, side)
    assert [t.t0 for t in stated] == [r["t"] for r in side["reversals"]]
    # the rate: the first segment's direction at the start, the last one's at the end
    assert np.sign(run["gammadot"].iloc[0]) == directions[0] and np.sign(run["gammadot"].iloc[-1]) == directions[-1]
    return side, run


# --- model-made data -----------------------------------------------------------------------

#: Model 1 coefficients the calibration round trips recover (Eq. 6; tests/test_calibrate_roundtrip.py).
TRUTH_M1 = dict(a1=-0.85, b1=0.0, c1=-3000.0, a2=-5.0, b2=100.0, c2=2000.0, X_c=0.0827)


def truth_params():
    """The default parameters with Model 1's coefficients set to ``TRUTH_M1``."""
    d = default_params().to_dict()
    d["model1"] = dict(TRUTH_M1)
    return params_from_dict(d)


# --- model-made noisy comparisons (the claims tests) -------------------------------------------

NOISE_LENGTH = 0.01    # strain over which the DEM's noise stays correlated (a few contact lifetimes)
# Noise of a cell 16 times larger than the 500-disk reference (noise ~ N^-1/2). At the 500-disk level four
# seeds cannot tell the models apart on the early |A| (the noisy pre-reversal fabric moves Model 1's start
# along its pole): the table then says "inconclusive" or worse, which is the power question, not this test's.
NOISE_SCALE = 0.25


def strong_pole_params():
    """Model 1 with a strong pole (c_i five times the defaults); Model 2 = Model 1's linear part."""
    d = default_params().to_dict()
    d.pop("provenance", None)
    d["model1"].update(c1=-1000.0, c2=5000.0)
    return params_from_dict(d)


def ar1_noise(rng, s, sd, length):
    """Gaussian noise of standard deviation ``sd`` correlated over ``length`` of strain (AR(1) on the samples)."""
    e = np.empty(len(s))
    e[0] = rng.normal(0.0, sd)
    r = np.exp(-np.abs(np.diff(s)) / length)
    for i in range(1, len(s)):
        e[i] = r[i - 1] * e[i - 1] + np.sqrt(1.0 - r[i - 1] ** 2) * rng.normal(0.0, sd)
    return e


def add_correlated_noise(case, seed, scale=NOISE_SCALE):
    """Serially correlated noise on a model-made case's fabric and shear stress, ``scale`` x one 500-disk run's."""
    rng = np.random.default_rng(1000 + seed)
    for stage in ("preshear", "heaviside", "sinusoidal"):
        path = case / f"{stage}.csv"
        d = pd.read_csv(path)
        s = np.abs(d["strain"] - d["strain"].iloc[0]).to_numpy()
        for c in ("A_xx", "A_xy"):
            d[c] += ar1_noise(rng, s, scale * FABRIC_NOISE, NOISE_LENGTH)
        d["sigma_xy"] += ar1_noise(rng, s, scale * MU_NOISE, NOISE_LENGTH)
        d["mu"] = np.abs(d["sigma_xy"]) / d["p"]
        d.to_csv(path, index=False)


def comparison_for_truth(root, truth):
    """4 noisy seeds made by ``truth`` under ``root/dem``, compared with both models at the known parameters."""
    params = strong_pole_params()
    dirs = write_ensemble(root / "dem", params, seeds=(1, 2, 3, 4), model=truth,
                          friction="eq2" if truth == "model1" else "quadratic",
                          preshear_strain=0.5, reversal_strain=0.6, coarse=0.005)
    for k, d in enumerate(dirs):
        add_correlated_noise(d, k)
    save_params(params, root / "params.yaml")
    c = comparison.run(dirs, root / "params.yaml", ["heaviside", "sinusoidal"], set_name="other", train_cases=[])
    return dirs, c


def table_of(dirs, c):
    """Claims table of a comparison's curves (every run out of sample: the comparison had train_cases=[])."""
    pred = c.predictions.assign(in_sample=False)
    return claims_table(pred, [read_dem_case(d) for d in dirs], eq2=None, n_resamples=1000).set_index("claim_id")


#: A tiny real campaign (two seeds of a 5d x 10d cell, seconds of YADE each): the workflow tests' own preset.
TINY = {
    "campaign": "tiny",
    "loading": {"pressures": [1.0e5], "inertial_numbers": [1.0e-2]},
    "seeds": [1, 2],
    "cell": {"H_over_d": 5, "W_over_H": 2},
    "material": {"diameter": 1.0e-3, "density": 2500.0, "kappa": 1.0e3, "kt_over_kn": 0.5,
                 "restitution": 0.5, "friction": 0.45, "size_ratio_min": 0.5, "size_ratio_max": 1.5},
    "timestep": {"dt_over_tc": 0.1},
    "pack": {"initial_solid_fraction": 0.4, "solid_fraction_guess": 0.8},
    "preshear": {"strain": 0.2},
    "protocols": {"heaviside": {"strain": 0.05}},
    # 126 and 51 rows: calibrate's 50 per file (the pre-flight check asks for them)
    "sampling": {"fine_interval": 0.001, "fine_window": 0.05, "coarse_interval": 0.002, "bulk_exclusion_d": 1},
    "run": {"checkpoint_every_s": 60, "progress_every_s": 10},
    "calibration": {"options": "--bootstrap 8"},
    "accuracy": {"ode_work_precision": False},
}


# --- Snakemake -----------------------------------------------------------------------------

def workflow_copy(folder):
    """Make ``folder`` a working copy of the workflow (symbolic links to the repository's code and
    configs, nothing of its results or .snakemake/) and return it."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for entry in ROOT.iterdir():
        if entry.name in NOT_COPIED or entry.name.startswith("results"):
            continue
        link = folder / entry.name
        if not link.exists():
            link.symlink_to(entry)
    return folder


def snakemake(*args, cwd, timeout=300):
    """Run ``snakemake *args`` in ``cwd`` (a ``workflow_copy``, never the repository itself)."""
    if Path(cwd).resolve() == ROOT:
        raise ValueError("run Snakemake in a workflow_copy, not in the repository (its .snakemake/ is shared)")
    return subprocess.run([*SNAKEMAKE, *map(str, args)], cwd=cwd, capture_output=True, text=True,
                          timeout=timeout)


def dry_run(*args, cwd, quiet=True, timeout=300):
    """Snakemake's dry run (``-n``) of ``args`` in ``cwd``; with ``quiet`` only its job table
    (``--quiet rules``, put last: its choices would swallow targets placed after it)."""
    return snakemake("-n", *args, *(["--quiet", "rules"] if quiet else []), cwd=cwd, timeout=timeout)


def counts(stdout):
    """rule -> number of jobs, from the job table of a dry run."""
    out = {}
    for line in stdout.splitlines():
        parts = line.split()
        if len(parts) == 2 and parts[1].isdigit():
            out[parts[0]] = int(parts[1])
    return out


def run_main(module: str, argv, package: str | None = None) -> subprocess.CompletedProcess:
    """``python -m <package> argv...`` in this process: ``module``'s ``main(argv)`` (the function the
    package's ``__main__`` hands its arguments to), with stdout, stderr and every warning captured as a
    process of its own would print them, and argparse's exit turned into the exit code. A process of
    its own would spend 1 to 1.6 s of CPU importing what this one has imported already.

    ``package`` (default: ``module``'s first part) names ``sys.argv[0]`` as under ``python -m``, for
    argparse's program name. Returns a CompletedProcess."""
    package = package or module.split(".")[0]
    main = importlib.import_module(module).main
    out, err = io.StringIO(), io.StringIO()
    saved = sys.argv
    sys.argv = [str(ROOT / package / "__main__.py"), *map(str, argv)]
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), warnings.catch_warnings():
            warnings.simplefilter("always")                  # printed, as a fresh process prints them
            warnings.showwarning = lambda message, category, filename, lineno, file=None, line=None: err.write(
                warnings.formatwarning(message, category, filename, lineno, line))
            try:
                code = main(list(map(str, argv)))
            except SystemExit as exc:                       # argparse's own errors
                code = exc.code
    finally:
        sys.argv = saved
    return subprocess.CompletedProcess(["python", "-m", package, *map(str, argv)], code or 0, out.getvalue(),
                                       err.getvalue())


def preflight_check(*configfiles):
    """``python -m preflight check configfiles...``, in-process (``run_main``; the Snakefile's gate runs the
    same ``preflight.check`` before any job, in milliseconds rather than a dry run's seconds).
    tests/test_campaign_preflight.py runs representative cases through the real ``snakemake -n`` as well."""
    return run_main("preflight.__main__", ["check", *configfiles])


def workflow_rules(workdir, *configfiles, config=None):
    """The rules of the workflow in ``workdir`` (a ``workflow_copy``) parsed with ``configfiles`` (later ones
    override earlier ones) and the ``--config`` values ``config``, through Snakemake's API (no job runs):
    their names, shell commands and outputs with their flags."""
    from snakemake.api import SnakemakeApi
    from snakemake.settings.types import ConfigSettings, OutputSettings, ResourceSettings, StorageSettings

    with SnakemakeApi(OutputSettings()) as api:
        workflow = api.workflow(
            resource_settings=ResourceSettings(), storage_settings=StorageSettings(),
            config_settings=ConfigSettings(configfiles=[Path(f) for f in configfiles], config=config or {}),
            snakefile=Path(workdir) / "Snakefile", workdir=Path(workdir))
        return list(workflow._workflow.rules)
