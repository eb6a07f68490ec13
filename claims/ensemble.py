r"""The DEM's seed ensemble: its noise floor per reversal position, and the scatter of its crossings (issue 32).

A DEM run is one draw of the ensemble at its reversal position (a protocol's
reversal: ``sinusoidal``, ``train03_r2``, ...; the keys of ``predictions.csv``):
:math:`d_i(s) = \mu(s) + \varepsilon_i(s)`, with :math:`\mu` the ensemble's
mean response and :math:`\varepsilon_i` the seed's own deviation, of variance
:math:`\sigma^2(s)` over seeds. A model curve :math:`m_i` scored against the
run has, over the window :math:`W` after the reversal,

.. math:: \mathrm{E}\,\mathrm{MSE}_i = \underbrace{\overline{(m_i - \mu)^2}}_{B^2:\ \text{model error}}
          + \underbrace{\overline{\sigma^2}}_{\text{noise floor}}

(bars: means over the samples of :math:`W`; the model's deviation independent
of the run's noise). So

- the **noise floor** :math:`N = \overline{\sigma^2}` of a position is
  measured from the seed-to-seed scatter: the unbiased variance over seeds
  of the DEM curves (``ddof=1``) at every sample of the window (each seed
  interpolated onto the first seed's samples), averaged over the window
  (``noise_floors``). It includes the start states' differences between
  seeds, which the models follow in part (each run is predicted from its own
  start state), so it is an upper bound of the noise the models cannot
  predict;
- the **model error** :math:`B^2 = \mathrm{MSE} - N` scores a perfect model
  about 0, whatever the noise;
- the difference of two models on the same run,
  :math:`\mathrm{MSE}_1 - \mathrm{MSE}_2`, estimates :math:`B_1^2 - B_2^2`
  with no floor to estimate: it cancels (a difference of RMSEs,
  :math:`\sqrt{B_1^2 + N} - \sqrt{B_2^2 + N}`, is compressed by it: with
  the release's floor a perfect model could beat Model 2 by at most a fifth
  of Model 2's model error);
- a model **lies within the DEM's ensemble band** when :math:`B^2 \le N`: its
  curve is, in RMS over the window, within one seed-to-seed s.d. of the
  ensemble's mean, as close as another seed of the DEM (the band Figs. 4-5
  draw, ``compare.figures``). Per run :math:`\mathrm{MSE} - 2N` estimates
  :math:`B^2 - N` (``claims.table``'s adequacy test).

Crossings (claims 3 and 5). The A_xx where A_xy first changes sign
(``dem_contract.passage``) is judged per run against the pooled
seed-to-seed scatter of the other runs' crossings at the same positions
(``crossing_z``, leave one out): it holds every source of noise at the
crossing (the fabric's, the crossing's location), measured where the
crossing is, not on the run's tail (whose smoothed, coarsely sampled noise
is about half the crossing's at the DEM's sampling: a z of s.d. about 2
under no effect), and a real difference between seeds only makes it larger
(the tests conservative).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


def by_position(dem: dict) -> dict:
    """(group, protocol) -> {case: curve} from ``claims.inputs.dem_curves``' (case, group, protocol) -> curve."""
    out = {}
    for (case, group, proto), d in dem.items():
        out.setdefault((group, proto), {})[case] = d
    return out


@dataclass
class Floor:
    """The seed-to-seed variance of one DEM column at one reversal position, over the early window."""

    s: np.ndarray        # the samples of the window (the first seed's, 0 < s <= window)
    var: np.ndarray      # the unbiased variance over seeds at each sample
    seeds: int

    @property
    def mean(self) -> float:
        """The noise floor :math:`N`: the variance averaged over the window (NaN with fewer than 2 seeds)."""
        return float(np.mean(self.var)) if self.seeds >= 2 and self.var.size else math.nan


def noise_floors(dem: dict, column: str, window: float) -> dict:
    """(group, protocol) -> ``Floor`` of ``column`` over the first ``window`` strain (module docstring).

    Parameters
    ----------
    dem : dict
        ``claims.inputs.dem_curves``: (case, group, protocol) -> the DEM curve (``s_rev`` and ``column``).
    """
    out = {}
    for pos, curves in by_position(dem).items():
        cases = sorted(curves)
        first = curves[cases[0]]
        s = first["s_rev"].to_numpy(float)
        s = s[(s > 0) & (s <= window)]
        ys = np.array([np.interp(s, curves[c]["s_rev"].to_numpy(float), curves[c][column].to_numpy(float))
                       for c in cases])
        var = ys.var(axis=0, ddof=1) if len(cases) >= 2 else np.full(s.size, math.nan)
        out[pos] = Floor(s=s, var=var, seeds=len(cases))
    return out


def crossing_z(crossings: dict) -> dict:
    r"""Each run's crossing over the pooled seed-to-seed scatter of the other runs' crossings (leave one out).

    .. math:: z_r = \frac{x_r}{s_{(-r)}}, \qquad
              s_{(-r)}^2 = \frac{\sum_p \sum_{i \in p,\, i \ne r} (x_{ip} - \bar x_{p(-r)})^2}{\sum_p (k_{p(-r)} - 1)}

    over the reversal positions :math:`p` (``by_position``) and their crossings
    :math:`x_{ip}` (A_xx where A_xy first changes sign, one per seed),
    :math:`\bar x_{p(-r)}` the mean of position :math:`p` without run :math:`r`.
    With the run left out, :math:`x_r` and :math:`s_{(-r)}` are independent: under
    "the run crosses at A_xx = 0" (the edge of "through 90 degrees") :math:`z_r`
    follows Student's t with the degrees of freedom of :math:`s_{(-r)}`; a real
    difference between seeds only makes :math:`s_{(-r)}` larger (conservative),
    and a run that really crosses the other axis does not widen its own yardstick.

    Parameters
    ----------
    crossings : dict
        (case, group, protocol) -> A_xx at the crossing (NaN: no crossing).

    Returns
    -------
    dict
        The same keys (finite crossings only) -> (z, degrees of freedom); z NaN with no degree of freedom.
    """
    by_pos = {}
    for key, x in crossings.items():
        if np.isfinite(x):
            by_pos.setdefault((key[1], key[2]), []).append((key, float(x)))

    def ss(xs):
        v = np.asarray(xs, float)
        return (float(((v - v.mean()) ** 2).sum()), v.size - 1) if v.size >= 2 else (0.0, 0)

    total = {pos: ss([x for _, x in runs]) for pos, runs in by_pos.items()}
    ss_all, dof_all = sum(s for s, _ in total.values()), sum(d for _, d in total.values())
    out = {}
    for pos, runs in by_pos.items():
        for key, x in runs:
            s_out, d_out = ss([y for k, y in runs if k != key])
            s2, dof = ss_all - total[pos][0] + s_out, dof_all - total[pos][1] + d_out
            out[key] = (x / math.sqrt(s2 / dof) if dof and s2 > 0 else
                        (math.copysign(math.inf, x) if dof and x else math.nan), dof)
    return out
