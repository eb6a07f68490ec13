"""The stage's failures, one exit code each (run_stage.py)."""


class GuardError(RuntimeError):
    """A guard fired: the run stops with exit code 3."""


class InputError(RuntimeError):
    """A missing or mismatched input: exit code 2."""


class Interrupted(RuntimeError):
    """SIGTERM or SIGINT: a checkpoint was written, exit code 4; rerun to resume."""
