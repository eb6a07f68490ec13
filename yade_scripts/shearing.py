"""Shearing and its driving: the pre-shear's wall speeds, a reversal stage's schedule of
segments (scene.segments) and the half-cosine turn of the wall speed.

A segment boundary falls between two run chunks (stages.Stage.run asks
`_next_boundary`), where `_enter_segment` writes the row just before a reversal and
turns the wall speed, at once or through a per-step PyRunner (`wall_speed`).
A mixin of stages.Stage.
"""
import json
import math
import os

import build
import engines
import scene as scenemod
from stageerrors import InputError
from yade.wrapper import Omega

O = Omega()
PREVIOUS = {"preshear": "pack"}  # every reversal stage (heaviside, sinusoidal, a schedule) starts from the pre-shear


class Shearing:
    def _start_from_previous(self, st, steps_per_strain):
        """The pre-shear from the packing, a reversal stage from the pre-shear: load the previous
        stage's final state, set the wall speeds (or plan the reversal schedule)."""
        der, sc, smp = self.der, self.scene, self.scene["sampling"]
        before = PREVIOUS.get(self.stage, "preshear")
        prev = os.path.join(self.case_dir, f"{before}.final.yade.gz")
        if not os.path.exists(prev):
            raise InputError(f"missing input {prev}: run stage {before} first")
        O.load(prev)
        self.lay = build.layout()
        pst = json.loads(O.tags["ys_state"])
        if pst.get("scene_sha256") != self.hash:
            print(f"[{self.stage}] warning: {prev} was made from another scene file", flush=True)
        st.update(dt=pst["dt"], t_origin=pst["t_origin"], strain=pst["strain"], iter0=O.iter,
                  time0=O.time, load=der["p"] * der["W"] * der["d"])
        if self.stage == "preshear":
            st["t_origin"] = O.time
            st["strain"] = 0.0
        st["strain_start"], st["t_start"] = st["strain"], (O.time - st["t_origin"]) / der["T0"]
        st["n_transition"] = 0
        if self.stage == "preshear":
            st["n_steps"] = int(math.ceil(sc["preshear"]["strain"] * steps_per_strain))
            st["fine_end"] = O.iter + int(math.ceil(smp["fine_window"] * steps_per_strain))
            build.set_wall_speeds(self.lay, der["U"], -der["U"])
        else:
            self._plan_schedule(steps_per_strain)
        st["every"] = st["fine_every"]

    def _plan_schedule(self, steps_per_strain):
        """The reversal stage's segments in steps (scene.segments), and the start of the first.

        Segment k runs from step start_k = ceil(S_k * steps_per_strain) since the stage's start,
        S_k the strain at full rate of the segments before it, to start_{k+1}; a segment whose
        direction differs from the one before it (the pre-shear's, +1, for the first) starts
        with a reversal: sharp (heaviside) or a half cosine of the wall speed over
        ceil(transition_strain * steps_per_strain) steps.
        """
        st, smp = self.st, self.scene["sampling"]
        segs, at, plan = scenemod.segments(self.scene, self.stage), 0.0, []
        for seg in segs:
            n_tr = (int(math.ceil(seg["transition_strain"] * steps_per_strain))
                    if seg["transition"] == "half_cosine" else 0)
            plan.append(dict(seg, start=int(math.ceil(at * steps_per_strain)), n_transition=n_tr))
            at += seg["strain"]
        st["segments"], st["segment"], st["direction"] = plan, -1, 1
        st["n_steps"] = int(math.ceil(at * steps_per_strain))
        st["fine_window_steps"] = int(math.ceil(smp["fine_window"] * steps_per_strain))
        st["reversals"] = []
        # fine sampling from the stage's start, as in the pre-shear (a first segment that reverses restarts it)
        st["fine_end"] = O.iter + st["fine_window_steps"]
        self._enter_segment(0, at_start=True)

    def _next_boundary(self):
        """Steps since the stage's start at which the next segment begins (None: in the last one)."""
        st = self.st
        k = st.get("segment", -1) + 1
        if self.stage == "preshear" or self.stage == "pack" or k >= len(st["segments"]):
            return None
        return st["segments"][k]["start"]

    def _enter_segment(self, k, at_start=False):
        """Start segment k between two steps: a row for the state just before a reversal
        (not at the stage's start: its contact forces are not saved with the state), the
        new wall speeds (or the half cosine towards them), fine sampling from here on."""
        st, der = self.st, self.der
        seg = st["segments"][k]
        reverses = seg["direction"] != st["direction"]
        if reverses and not at_start:
            self._sample()
            if self.error is not None:
                raise self.error
        st["segment"] = k
        if reverses:
            st["reversals"].append(dict(strain=st["strain"], t=(O.time - st["t_origin"]) / der["T0"],
                                        direction=seg["direction"], transition=seg["transition"],
                                        **({"transition_strain": seg["transition_strain"]}
                                           if seg["transition"] == "half_cosine" else {})))
            st["tr_iter0"], st["tr_from"] = O.iter, st["direction"]
            # the pressure guard's window restarts at each reversal, as at the stage's start: the
            # wall pressure dips for a few percent of strain after every reversal, physically
            st["window"], st["guard_from"] = [], (O.iter - st["iter0"]) * der["dt"] * der["gammadot"]
            st["n_transition"] = seg["n_transition"]
            st["fine_end"] = O.iter + seg["n_transition"] + st["fine_window_steps"]
        st["direction"] = seg["direction"]
        U, d0 = der["U"], st.get("tr_from", 1)
        if reverses and seg["n_transition"] > 0:
            build.set_wall_speeds(self.lay, d0 * U, -d0 * U)  # the half cosine starts at the old speed
        else:
            build.set_wall_speeds(self.lay, seg["direction"] * U, -seg["direction"] * U)
        if not at_start and reverses:
            if seg["n_transition"] > 0:
                self._install_wall_runner(seg["n_transition"] + 1)
            sampler = self.sampler
            sampler.iterPeriod = st["fine_every"]
            sampler.iterLast = st["last_sample_iter"] - 1  # the fine grid starts at the reversal
            sampler.nDone = max(1, sampler.nDone)

    def _install_wall_runner(self, n):
        """A per-step PyRunner setting the wall speed for the next n steps, inserted before the sampler."""
        eng = [e for e in O.engines if e.label != "wallspeed"]
        k = next(i for i, e in enumerate(eng) if e.label in ("flip", "sampler"))
        O.engines = eng[:k] + [engines.PyRunner(command="_ys_wall()", iterPeriod=1, nDo=n, label="wallspeed")] + eng[k:]
        self.engine_names = engines.describe(O.engines)

    def wall_speed(self):
        r"""Half cosine of the top wall speed from a U to b U over the transition, then b U.

        .. math:: u(x) = U\left[\tfrac12(a + b) + \tfrac12(a - b)\cos\pi x\right],\quad
                  x = \min(1, k / n_{tr})

        a, b the directions before and after the reversal, k the steps since its start
        (a = 1, b = -1: U cos(pi x), the sinusoidal protocol).
        """
        st = self.st
        k = O.iter + 1 - st["tr_iter0"]
        x = min(1.0, k / st["n_transition"])
        a, b = st["tr_from"], st["direction"]
        u = self.der["U"] * (0.5 * (a + b) + 0.5 * (a - b) * math.cos(math.pi * x))
        build.set_wall_speeds(self.lay, u, -u)
