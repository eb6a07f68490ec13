"""Independent jobs run side by side, their model integrations batched: one ``simulate_batch`` call per round.

Bootstrap replicates, profile chains and free-form folds are independent jobs,
each a sequence of fits whose every step integrates the model along the replays
(``curves_integration.curves``). ``IntegrationBatcher.run`` runs each job in a
thread of its own and hands it the batcher; the job passes it to every
``curves`` call it makes. A request waits at the batcher until every job still
running waits on one; then all waiting requests are integrated together
(``curves_integration.integrate_requests``) and each job gets its part. A
trajectory's numbers do not depend on the rest of its batch (model/README.md),
so each job gets what it would get alone: only the number of numpy passes changes.
"""
from __future__ import annotations

import threading

from .curves_integration import integrate_requests


class IntegrationBatcher:
    """Run jobs in threads whose ``curves`` requests are integrated together, one batch per round.

    When every job still running is waiting on a request, the last to arrive
    integrates all requests (those with the same tolerances in one
    ``simulate_batch`` call) and hands each its part. ``run`` returns what
    running the jobs one after the other would.
    """

    def __init__(self):
        self._cv = threading.Condition()
        self._pending, self._active = [], 0

    def run(self, jobs) -> list:
        """Call every job with this batcher, each in its own thread; their results, or raise the first error.

        Parameters
        ----------
        jobs : list of callable
            ``job(batcher)``: the job passes ``batcher`` on to its ``curves`` calls.
        """
        results, errors = [None] * len(jobs), [None] * len(jobs)
        self._active = len(jobs)

        def work(k):
            try:
                results[k] = jobs[k](self)
            except BaseException as exc:   # re-raised below, in the caller's thread
                errors[k] = exc
            finally:
                with self._cv:
                    self._active -= 1
                    self._flush_if_ready()

        threads = [threading.Thread(target=work, args=(k,), daemon=True) for k in range(len(jobs))]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        for e in errors:
            if e is not None:
                raise e
        return results

    def submit(self, request):
        """Wait with ``request`` (items, replays, settings) for this round's batch; its part of the batch."""
        slot = {"request": request}
        with self._cv:
            self._pending.append(slot)
            self._flush_if_ready()
            self._cv.wait_for(lambda: "out" in slot)
        if isinstance(slot["out"], BaseException):
            raise slot["out"]
        return slot["out"]

    def _flush_if_ready(self):
        if not self._pending or len(self._pending) < self._active:
            return
        slots, self._pending = self._pending, []
        groups = {}   # requests with the same tolerances share a batch
        for s in slots:
            st = s["request"][2]
            groups.setdefault((st.rtol, st.atol, st.method, st.max_steps), []).append(s)
        for group in groups.values():
            try:
                outs = integrate_requests([s["request"] for s in group])
            except Exception as exc:   # a bad request: every job waiting on this batch gets the error
                outs = [exc] * len(group)
            for s, o in zip(group, outs):
                s["out"] = o
        self._cv.notify_all()


def run_jobs(jobs, settings) -> list:
    """Every job's result: side by side under one ``IntegrationBatcher`` with the batched integrator, else in turn.

    Parameters
    ----------
    jobs : list of callable
        ``job(batcher)``; with the loop integrator ``batcher`` is None (the loop integrates at once).
    settings : curves_integration.CurvesSettings
    """
    if settings.integrator == "batched":
        return IntegrationBatcher().run(jobs)
    return [job(None) for job in jobs]
