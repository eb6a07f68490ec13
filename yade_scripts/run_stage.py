"""Entry point: python3 yade_scripts/run_stage.py <scene.json> <stage> <case_dir> [--log <file>]

Runs one stage (pack, preshear, heaviside, sinusoidal, or a reversal schedule named in the
scene's `schedules` section) of one case; see docs/scene.md.

YADE is imported as a library (yadelib): no TCP Python prompt, no XMLRPC server, no
auth cookie in the log. Any `python3` may start the script: it runs itself again under
the interpreter the `yade` launcher names (YADE's compiled modules are built for it).
Under the launcher itself (`yade -x`, whose remote servers are then open) it refuses.

The order is: the scene (no YADE), the stage lock (no YADE: a refusal is cheap and
immediate), the log (`--log`: opened only once the lock is held, see stagelog), YADE.
Exit codes: 0 done, 1 unexpected error, 2 bad scene, missing input or YADE not found,
3 guard fired, 4 interrupted by SIGTERM or SIGINT (checkpoint written: rerun to resume),
5 another live process runs this stage of this case (nothing touched, the log included).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(sys.argv[0])))

import stagecli  # noqa: E402
import yadelib  # noqa: E402


def main(argv):
    if yadelib.under_the_launcher():
        print("run_stage.py is not run by the yade launcher (it opens a TCP Python prompt and an "
              "XMLRPC server for the life of the stage): " + stagecli.usage("yade").removeprefix("usage: "),
              file=sys.stderr)
        return 2
    return stagecli.main(argv, "yade", run)


def run(scene, sha, stage, case_dir, renew):
    try:
        yadelib.import_yade()
    except (yadelib.YadeNotFound, ImportError) as e:
        print(f"YADE not found: {e}", file=sys.stderr)
        return 2
    import stages  # YADE imports only once the scene is known to be good and the stage is ours

    return stagecli.run_stage(stages.Stage(scene, sha, stage, case_dir), renew)


if __name__ == "__main__":  # also under the launcher (`yade -x` runs a script as __main__)
    if not yadelib.under_the_launcher():
        try:
            yadelib.run_under_yade_interpreter()
        except yadelib.YadeNotFound as e:
            print(f"YADE not found: {e}", file=sys.stderr)
            os._exit(2)
    stagecli.leave(lambda: main(sys.argv[1:]))
