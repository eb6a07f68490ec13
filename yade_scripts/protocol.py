"""A reversal stage's protocol: its segments in steps and the walls' speed at every step.

Pure Python (no YADE, no LAMMPS): yade_scripts/shearing.py and lammps_scripts/shearing.py drive
their walls through it, so that a Heaviside reversal, the sinusoidal one and every reversal
schedule or train (docs/scene.md, "Reversal schedules") mean the same steps and speeds in both
engines, and their sidecars carry the same keys (docs/data-contract.md).

The protocol (scene.segments): segment k runs from step start_k = ceil(S_k * steps_per_strain)
since the stage's start, S_k the strain at full rate of the segments before it; a segment whose
direction differs from the one before it (+1, the pre-shear's, for the first) starts with a
reversal, sharp (heaviside) or a half cosine of the wall speed over
n_tr = ceil(transition_strain * steps_per_strain) steps (`half_cosine_speed`).

The stage's state ``st`` (a dict, saved with every checkpoint) holds the plan and where the
stage is in it: ``segments`` (each with ``start`` and ``n_transition``), ``segment`` (the
current one), ``direction``, ``reversals`` (one record per reversal so far), and for the last
reversal ``tr_iter0`` (its step), ``tr_from`` (the direction before it), ``n_transition``.
"""
import math


def plan(st, segs, fine_window, steps_per_strain, it):
    """Plan a reversal stage of segments ``segs`` (scene.segments) starting at step ``it``, into ``st``.

    Sets st's ``segments`` (``segs``, each with ``start`` and ``n_transition`` in steps),
    ``segment`` = -1 (none entered yet: `enter` segment 0 next, at the stage's start),
    ``direction`` = +1 (the pre-shear's), ``n_steps`` (the stage's steps: the sum of the
    segments' strains at full rate), ``fine_window_steps`` (``fine_window``, the scene's
    sampling.fine_window, in steps),
    ``reversals`` = [] and ``fine_end`` (fine sampling from the stage's start, as in the
    pre-shear; a reversal restarts it).
    """
    at, out = 0.0, []
    for seg in segs:
        n_tr = (int(math.ceil(seg["transition_strain"] * steps_per_strain))
                if seg["transition"] == "half_cosine" else 0)
        out.append(dict(seg, start=int(math.ceil(at * steps_per_strain)), n_transition=n_tr))
        at += seg["strain"]
    st["segments"], st["segment"], st["direction"] = out, -1, 1
    st["n_steps"] = int(math.ceil(at * steps_per_strain))
    st["fine_window_steps"] = int(math.ceil(fine_window * steps_per_strain))
    st["reversals"] = []
    st["fine_end"] = it + st["fine_window_steps"]


def next_boundary(st):
    """Steps since the stage's start at which the next segment begins; None in the last segment
    or in a stage without segments (pack, pre-shear)."""
    if "segments" not in st:
        return None
    k = st["segment"] + 1
    return st["segments"][k]["start"] if k < len(st["segments"]) else None


def reverses(st, k):
    """True when segment k turns the walls (its direction differs from the current one)."""
    return st["segments"][k]["direction"] != st["direction"]


def enter(st, k, it, t, der):
    """Enter segment k at step ``it`` (between two steps; ``t`` the time since the time origin
    in the series' unit): record its reversal if it reverses, and return the top wall's speed
    to set now (m/s; the bottom wall's is its opposite).

    A reversal appends {strain, t, direction, transition[, transition_strain]} to
    st['reversals'], restarts the pressure guard's window (the wall pressure dips for a few
    percent of strain after every reversal, physically: ``window``, ``guard_from``) and fine
    sampling (until n_tr + fine_window steps after it), and starts the half cosine (``tr_iter0``,
    ``tr_from``, ``n_transition``). The speed now is the new direction's, or with a half cosine
    the old one (`half_cosine_speed` turns it step by step: `transition_speed`).
    The caller samples the state just before a reversal (`reverses`) first, but not at the
    stage's start (its contact forces are those of the previous stage's end).
    """
    seg = st["segments"][k]
    turn = reverses(st, k)
    st["segment"] = k
    if turn:
        st["reversals"].append(dict(strain=st["strain"], t=t, direction=seg["direction"],
                                    transition=seg["transition"],
                                    **({"transition_strain": seg["transition_strain"]}
                                       if seg["transition"] == "half_cosine" else {})))
        st["tr_iter0"], st["tr_from"] = it, st["direction"]
        st["window"], st["guard_from"] = [], (it - st["iter0"]) * der["dt"] * der["gammadot"]
        st["n_transition"] = seg["n_transition"]
        st["fine_end"] = it + seg["n_transition"] + st["fine_window_steps"]
    st["direction"] = seg["direction"]
    if turn and seg["n_transition"] > 0:
        return st.get("tr_from", 1) * der["U"]  # the half cosine starts at the old speed
    return seg["direction"] * der["U"]


def in_transition(st, it):
    """True while the wall speed is still to be set after the step that starts at step ``it``
    (the steps tr_iter0 + 1 .. tr_iter0 + n_tr of the last half cosine)."""
    return st.get("n_transition", 0) > 0 and it < st["tr_iter0"] + st["n_transition"]


def transition_speed(st, der, it):
    """The top wall's speed (m/s) at the end of step ``it`` (the state after it) in the last
    reversal's half cosine: `half_cosine_speed` at k = it - tr_iter0 steps into it."""
    return half_cosine_speed(der["U"], it - st["tr_iter0"], st["n_transition"], st["tr_from"], st["direction"])


def half_cosine_speed(U, k, n, a, b):
    r"""Half cosine of the top wall's speed from a U to b U over n steps (the sinusoidal protocol).

    .. math:: u(k) = U\left[\tfrac12(a + b) + \tfrac12(a - b)\cos\pi x\right],\quad
              x = \min(1, k / n)

    a, b the directions before and after the reversal (a = 1, b = -1: U cos(pi x)), k the steps
    since its start: the speed after step k, with which the wall moves through step k + 1
    (u(0) = a U through the first).
    """
    x = min(1.0, k / n)
    return U * (0.5 * (a + b) + 0.5 * (a - b) * math.cos(math.pi * x))


def sidecar_keys(stage, st):
    """A reversal stage's own sidecar keys (docs/data-contract.md): heaviside and sinusoidal
    reversal_strain, reversal_t (the stage's start); a schedule its first reversal's as those,
    every reversal (``reversals``) and its expanded ``segments``; sinusoidal transition_steps."""
    if stage in ("pack", "preshear"):
        return {}
    if stage in ("heaviside", "sinusoidal"):
        out = dict(reversal_strain=st["strain_start"], reversal_t=st["t_start"])
    else:
        out = dict(reversal_strain=st["reversals"][0]["strain"], reversal_t=st["reversals"][0]["t"],
                   reversals=st["reversals"],
                   segments=[{k: v for k, v in seg.items() if k not in ("start", "n_transition")}
                             for seg in st["segments"]])
    if stage == "sinusoidal":
        out["transition_steps"] = st["n_transition"]
    return out
