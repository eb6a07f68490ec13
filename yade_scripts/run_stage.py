"""Entry point: yade -n -x yade_scripts/run_stage.py <scene.json> <stage> <case_dir>

Runs one stage (pack, preshear, heaviside, sinusoidal, or a reversal schedule named in the
scene's `schedules` section) of one case; see docs/scene.md.
Exit codes: 0 done, 1 unexpected error, 2 bad scene or missing input, 3 guard fired,
4 interrupted by SIGTERM or SIGINT (checkpoint written: rerun to resume),
5 another live process runs this stage of this case (nothing touched).
"""
import os
import sys

# under `yade -x`, __file__ is /usr/bin/yade: find this directory from argv[0]
sys.path.insert(0, os.path.dirname(os.path.abspath(sys.argv[0])))

import scene as scenemod  # noqa: E402
import stagelock  # noqa: E402

USAGE = ("usage: yade -n -x yade_scripts/run_stage.py <scene.json> "
         "<pack|preshear|heaviside|sinusoidal|<schedule name>> <case_dir>")


def main(argv):
    if len(argv) != 3 or not (argv[1] in scenemod.STAGES or scenemod.PROTOCOL_NAME.match(argv[1])):
        print(USAGE, file=sys.stderr)
        return 2
    path, stage, case_dir = argv
    try:
        scene, sha = scenemod.load(path, stage)
    except scenemod.SceneError as e:
        print(e, file=sys.stderr)
        return 2
    import stages  # YADE imports only once the scene is known to be good

    stages.install_signal_handlers()
    lock = stagelock.StageLock(case_dir, stage, log=lambda line: print(line, flush=True))
    try:
        lock.acquire()
    except stagelock.Busy as e:
        print(f"busy: {e}", file=sys.stderr)
        return 5
    try:
        st = stages.Stage(scene, sha, stage, case_dir)
        st.prepare()
        st.run(lock)
    except stages.InputError as e:
        print(f"input error: {e}", file=sys.stderr)
        return 2
    except stages.GuardError as e:
        print(f"guard: {e}", file=sys.stderr)
        return 3
    except stages.Interrupted as e:
        print(f"interrupted: {e}", file=sys.stderr)
        return 4
    finally:
        lock.release()
    return 0


rc = main(sys.argv[1:])
sys.stdout.flush()
sys.stderr.flush()
if rc:
    os._exit(rc)
