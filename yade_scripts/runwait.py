"""Run YADE for n steps and wait for their end without YADE's 40 ms naps.

``O.run(n, True)`` waits in YADE's ``pyOmega.wait``, which looks at ``O.running`` every
40 ms: a run chunk returns on average 20 ms after its last step, about 2.6 % of the
stage's wall time with 1-second chunks (docs/findings.md, "The DEM stage against bare
YADE"). The steps themselves are the same either way.
"""
import time

LOOK_S = 0.001      # between looks at O.running near the predicted end
SLEEP_SHARE = 0.9   # of the predicted time slept in one go (less than all: see run_and_wait)


def run_and_wait(O, n, steps_per_s=None):
    """``O.run(n, True)`` with a finer wait; returns the steps per wall second of this run, or None.

    Sleeps through ``SLEEP_SHARE`` of the time ``steps_per_s`` (the last run's rate)
    predicts, then looks at ``O.running`` every ``LOOK_S``; without a rate it looks from
    the start. A run that had already ended when a sleep longer than one look did was
    overslept: its rate is only a lower bound (a prediction from it would sleep as long
    again, and the estimate would climb back by 1/SLEEP_SHARE per run), so it returns None
    and the next run is watched from its start. After a sleep shorter than a look the rate
    is as good as a watched run's. ``O.wait()`` at the end returns at once and, as
    ``O.run(n, True)`` does, raises what the simulation thread threw.
    """
    i0, t0 = O.iter, time.perf_counter()
    O.run(n)
    sleep_s = SLEEP_SHARE * n / steps_per_s if steps_per_s else 0.0
    time.sleep(sleep_s)
    overslept = sleep_s > LOOK_S and not O.running
    while O.running:
        time.sleep(LOOK_S)
    O.wait()
    return None if overslept else (O.iter - i0) / max(1e-6, time.perf_counter() - t0)
