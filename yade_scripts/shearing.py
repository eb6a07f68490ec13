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
import protocol
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
        """The reversal stage's segments in steps (protocol.plan), and the start of the first."""
        protocol.plan(self.st, scenemod.segments(self.scene, self.stage), self.scene["sampling"]["fine_window"],
                      steps_per_strain, O.iter)
        self._enter_segment(0, at_start=True)

    def _next_boundary(self):
        """Steps since the stage's start at which the next segment begins (None: in the last one)."""
        return protocol.next_boundary(self.st)

    def _enter_segment(self, k, at_start=False):
        """Start segment k between two steps (protocol.enter): a row for the state just before a
        reversal (not at the stage's start: its contact forces are not saved with the state),
        the new wall speeds (or the half cosine towards them), fine sampling from here on."""
        st, der = self.st, self.der
        turn = protocol.reverses(st, k)
        if turn and not at_start:
            self._sample()
            if self.error is not None:
                raise self.error
        u = protocol.enter(st, k, O.iter, (O.time - st["t_origin"]) / der["T0"], der)
        build.set_wall_speeds(self.lay, u, -u)
        if not at_start and turn:
            if st["n_transition"] > 0:
                self._install_wall_runner(st["n_transition"] + 1)
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
        """The top wall's speed in the half cosine (protocol.half_cosine_speed), set by a per-step
        PyRunner inside step O.iter: the speed after it, k = O.iter + 1 - tr_iter0 steps in."""
        u = protocol.transition_speed(self.st, self.der, O.iter + 1)
        build.set_wall_speeds(self.lay, u, -u)
