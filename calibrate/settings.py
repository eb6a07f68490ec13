"""The calibration's settings: every step's in one record, the defaults of ``python -m calibrate``.

One home for the defaults: the command line (``calibrate.__main__``) reads them
from here, and ``Settings.as_dict`` writes the record to params.yaml's provenance.
``steady_weight`` and ``xc_margin`` weigh the steady state and bound X_c in the
back-solve fit and the curve fit alike: the curve fit's record (``Settings.curves``)
is built from them, so the two routes cannot hold different values.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field

from . import backsolve, curves_integration, freeform, io, profiles, smoothing


@dataclass(frozen=True)
class Settings:
    """The settings of every step of ``pipeline.run``, each step's own record where it has one."""

    protocols: tuple = io.REVERSAL_PROTOCOLS
    smoothing: smoothing.SmoothingSettings = field(default_factory=smoothing.SmoothingSettings)
    backsolve: backsolve.BacksolveSettings = field(default_factory=backsolve.BacksolveSettings)
    curves_options: curves_integration.CurvesOptions = field(default_factory=curves_integration.CurvesOptions)
    steady_weight: float = 1.0
    xc_margin: float = 2e-3
    n_boot: int = 20
    boot_evals: int = 60
    seed: int = 0
    min_samples: int = io.MIN_SAMPLES
    figures: bool = True
    freeform: freeform.FreeformSettings | None = None   # None: no free-form fit (step 5b)
    profile: profiles.ProfileSettings = field(default_factory=profiles.ProfileSettings)

    @property
    def curves(self) -> curves_integration.CurvesSettings:
        """The curves route's settings: its options with this record's ``steady_weight`` and ``xc_margin``."""
        return curves_integration.CurvesSettings(**asdict(self.curves_options), steady_weight=self.steady_weight,
                                                 xc_margin=self.xc_margin)

    def as_dict(self) -> dict:
        """The record params.yaml keeps; the curves route's settings under ``route2``, the key released files carry."""
        return {"protocols": list(self.protocols), "smoothing": self.smoothing.as_dict(),
                "backsolve": self.backsolve.as_dict(), "route2": self.curves.as_dict(),
                "steady_weight": self.steady_weight, "xc_margin": self.xc_margin, "n_boot": self.n_boot,
                "boot_evals": self.boot_evals, "bootstrap_seed": self.seed, "min_samples": self.min_samples,
                "freeform": self.freeform.as_dict() if self.freeform else None,
                "profile": self.profile.as_dict()}
