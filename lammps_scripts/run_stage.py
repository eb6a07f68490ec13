"""Entry point: python3 lammps_scripts/run_stage.py <scene.json> <stage> <case_dir> [--log <file>]

Runs one stage (pack, preshear, heaviside) of one wall-cell case in LAMMPS, from the same
scene file as yade_scripts/run_stage.py (whose scene, stage lock, log and exit codes it shares:
yade_scripts/stagecli.py); the scene's `engine` must be "lammps". See docs/scene.md,
"The LAMMPS engine".

LAMMPS is loaded as a library (lammpslib) by the interpreter Debian's `python3-lammps` is
installed for: any `python3` may start the script, it runs itself again under that one.
Exit codes: 0 done, 1 unexpected error (a LAMMPS error ends the process with code 1 too:
Debian's library is built without exceptions; its message is in
`<case_dir>/.partial/<stage>/log.lammps`), 2 bad scene, missing input, a setting this engine
does not run, or LAMMPS not found, 3 guard fired, 4 interrupted by SIGTERM or SIGINT (checkpoint
written: rerun to resume, checkpoint.py), 5 another live process runs this stage.
"""
import os
import sys

HERE = os.path.dirname(os.path.abspath(sys.argv[0]))
sys.path[:0] = [HERE, os.path.join(os.path.dirname(HERE), "yade_scripts")]  # the shared pure modules

import lammpslib  # noqa: E402
import stagecli  # noqa: E402


def run(scene, sha, stage, case_dir, renew):
    import refusals

    why = refusals.refusals(scene, stage)
    if why:
        print("not supported by the lammps engine: " + "; ".join(why), file=sys.stderr)
        return 2
    try:
        import stages
    except ImportError as e:
        print(f"LAMMPS not found: {e}", file=sys.stderr)
        return 2
    try:
        return stagecli.run_stage(stages.Stage(scene, sha, stage, case_dir), renew)
    except lammpslib.LammpsNotFound as e:
        print(f"LAMMPS not found: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    try:
        lammpslib.run_under_lammps_interpreter()
    except lammpslib.LammpsNotFound as e:
        print(f"LAMMPS not found: {e}", file=sys.stderr)
        sys.exit(2)
    stagecli.leave(lambda: stagecli.main(sys.argv[1:], "lammps", run))
