r"""Power of the model comparisons: how much DEM decides a comparison row at the table's level.

Every model comparison of the claims table, per figure (claims 4 and 7, the
paper's configuration of Model 1 ``4-start-*``; ``claims.table.model_error_rows``),
is decided on the per-seed means :math:`d_i` of the paired out-of-sample
differences of squared model error. With their seed-to-seed standard
deviation :math:`s` and an effect :math:`\delta`, the power of ``n`` seeds is
the probability that the 90 % Student t interval of the mean lies entirely
on the effect's side of 0 (a one-sided test at 5 %: the table's one level,
``claims.stats``; the verdict "reproduced" for :math:`\delta < 0`):

.. math:: P(n) = 1 - F_{t'}\big(t_{0.95,\,n-1};\ n - 1,\ |\delta| \sqrt n / s\big)

with :math:`F_{t'}` the noncentral t distribution (``scipy.stats.nct``).
``seeds_needed`` is the smallest ``n`` with :math:`P(n) \ge 0.8`; for large ``n``
it approaches the normal closed form
:math:`n \approx \big((z_{0.95} + z_{0.8})\, s / \delta\big)^2`. The table's
interval is the wider of the t interval and a bootstrap, so this ``n`` is a
lower bound.

Two effects per row (``EFFECTS``):

- ``measured``: the table's point estimate (it may be about 0, then no
  volume is enough: ``n`` is infinite or beyond any campaign);
- ``minimal``: the smallest effect worth deciding, the row's margin (an
  improvement of Model 1 by the margin: ``claims.margins``).

DEM volume. Assumed: the per-seed differences are set by the DEM's noise,
which falls as :math:`N^{-1/2}` with the number of disks :math:`N` and as
:math:`k^{-1/2}` with the number of independent reversal transients :math:`k`
scored per seed, so

.. math:: s(N, k) = s_0 \sqrt{N_0 k_0 / (N k)}

and the volume seeds x disks x transients needed is about constant.
``fabric_noise_check`` tests the first half against the data: the per-sample
fabric noise of the steady pre-shear against that of independent contacts,
:math:`\operatorname{sd}(A_{xx}) = \operatorname{sd}(\cos 2\theta)/2 / \sqrt{n_c} = 1/\sqrt{8 n_c}`.
Core-hours use the measured CPU time of the campaign's DEM stages (the
sidecars' ``cpu_time_s``), scaled linearly with :math:`N` at the campaign's
contact stiffness, inertial number and time step; YADE's throughput per
particle-step falls about 3x from 500 to 5,000 disks (README), so at larger
:math:`N` this is a lower bound.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import yaml
from scipy import stats

from dem_contract import REVERSAL_PROTOCOLS, DEMInputError, read_series, stage_costs

from . import stats as claim_stats
from . import table

ALPHA = claim_stats.ALPHA         # one-sided, the table's one level
#: What power.csv and the README section say for a cost the DEM's sidecars do not record (a case with no
#: pack stage, data without timing sidecars or disk counts): the cost is unknown, not a number.
UNKNOWN = "unknown"
#: The columns of the power table that need the DEM's cost (disks, CPU time).
COST_COLUMNS = ("disks_per_seed", "particles", "core_hours")
POWER = 0.8
EFFECTS = ("measured", "minimal")
#: The comparison rows of the table the power is computed for: claim prefix -> quantity, window.
COMPARED = {"4": ("|A|", table.EARLY_A), "4-start": ("|A|", table.EARLY_A), "7": ("mu", table.EARLY_MU)}
N_MAX = 10**7     # seeds beyond this are reported as infinite
STAGES = ("pack", "preshear")
COLUMNS = ["claim_id", "quantity", "window", "effect_choice", "effect", "sd_per_seed", "seeds_measured",
           "disks_per_seed", "transients_per_seed", "seeds_needed", "transients", "particles", "core_hours",
           "power_measured"]


# --------------------------------------------------------------------------- the t-test's power


def power_t(n, sd: float, delta: float, alpha: float = ALPHA) -> float:
    r"""Probability that the one-sided level-``alpha`` t test of ``n`` values finds ``delta``'s side of 0
    (the two-sided (1 - 2 alpha) interval lies on that side).

    .. math:: P = 1 - F_{t'}\big(t_{1-\alpha,\,n-1};\ n-1,\ |\delta|\sqrt n/s\big)

    Parameters
    ----------
    n : int or float
        Number of independent values (seeds), at least 2.
    sd : float
        Their standard deviation.
    delta : float
        The true mean (the effect).
    """
    if n < 2 or not (np.isfinite(sd) and sd > 0 and np.isfinite(delta)):
        return math.nan
    df = n - 1
    crit = stats.t.ppf(1.0 - alpha, df)
    return float(stats.nct.sf(crit, df, abs(delta) * math.sqrt(n) / sd))


def normal_seeds(sd: float, delta: float, alpha: float = ALPHA, power: float = POWER) -> float:
    r"""The normal approximation :math:`n = \big((z_{1-\alpha} + z_{P})\, s/\delta\big)^2` (not rounded)."""
    if delta == 0:
        return math.inf
    return float(((stats.norm.ppf(1 - alpha) + stats.norm.ppf(power)) * sd / delta) ** 2)


def seeds_needed(sd: float, delta: float, alpha: float = ALPHA, power: float = POWER) -> float:
    """Smallest n >= 2 with ``power_t(n) >= power``; ``inf`` for no effect or beyond ``N_MAX``; NaN without sd.

    Iterates up from the normal approximation (the t test needs at least as many seeds).
    """
    if not (np.isfinite(sd) and sd > 0) or not np.isfinite(delta):
        return math.nan
    start = normal_seeds(sd, delta, alpha, power)
    if not start <= N_MAX:
        return math.inf
    n = max(2, int(math.floor(start)))
    while power_t(n, sd, delta, alpha) < power:
        n += 1
    return float(n)


def scaled_sd(sd0: float, disks0: float, transients0: float, disks: float, transients: float) -> float:
    r"""Per-seed s.d. at ``disks`` and ``transients`` per seed: :math:`s_0 \sqrt{N_0 k_0 / (N k)}`."""
    return float(sd0 * math.sqrt(disks0 * transients0 / (disks * transients)))


# --------------------------------------------------------------------------- what the campaign measured


def _sidecar(path) -> dict:
    try:
        return json.loads(Path(path).read_text())
    except (OSError, json.JSONDecodeError) as exc:
        raise DEMInputError(f"{path}: stage sidecar not readable ({exc})") from None


def _mean(values) -> float:
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    return float(v.mean()) if v.size else math.nan


def dem_cost(case_dirs, protocols) -> dict:
    """Disks and CPU seconds per case from the stage sidecars (``dem_contract.stage_costs``): means over the cases.

    Returns ``disks``, ``setup_cpu_s`` (packing and pre-shear), ``transient_cpu_s`` (one reversal run), NaN
    where the sidecars do not say (model-made cases; the means skip NaN), and ``geometry`` (``H_over_d``,
    ``W_over_H`` of the first case's scene.json, or None).
    """
    disks, setup, transient, geometry = [], [], [], None
    for d in map(Path, case_dirs):
        cost = stage_costs(d, (*STAGES, *protocols), keys=("cpu_time_s",), missing="nan")
        disks.append(cost["N"])
        setup.append(sum(cost[f"cpu_time_{st}_s"] for st in STAGES))
        transient += [cost[f"cpu_time_{p}_s"] for p in protocols]
        if geometry is None and (d / "scene.json").exists():
            geometry = _sidecar(d / "scene.json").get("geometry")
    return {"disks": _mean(disks), "setup_cpu_s": _mean(setup), "transient_cpu_s": _mean(transient),
            "geometry": geometry}


def fabric_noise_check(case_dirs) -> dict:
    r"""Per-sample fabric noise of the steady pre-shear against that of independent contacts.

    Measured: s.d. of A_xx and A_xy about a straight line over the last half of
    the pre-shear, pooled. Independent contacts of near-uniform orientation:
    :math:`1/\sqrt{8 \bar n_c}` (``n_contacts`` of the same samples). A ratio
    near 1 says the fabric noise is the sampling noise of the contacts, which
    falls as :math:`N^{-1/2}`.
    """
    measured, expected = [], []
    for d in map(Path, case_dirs):
        # n_contacts may be NaN (imported DEM data without contact counts): the expectation is then unknown
        pre = read_series(d / "preshear.csv", ("t", "strain", "A_xx", "A_xy", "n_contacts"), 10,
                          what="the pre-shear of the case", finite=("t", "strain", "A_xx", "A_xy"))
        pre = pre[pre["strain"].abs() >= pre["strain"].abs().max() / 2]
        s = pre["strain"].abs().to_numpy()
        for c in ("A_xx", "A_xy"):
            x = pre[c].to_numpy()
            measured.append(float(np.std(x - np.polyval(np.polyfit(s, x, 1), s), ddof=2)))
        expected.append(1.0 / math.sqrt(8.0 * pre["n_contacts"].mean()))
    m, e = float(np.mean(measured)), float(np.mean(expected))
    return {"measured": m, "independent_contacts": e, "ratio": m / e if np.isfinite(e) else math.nan}


def transients_per_seed(keys) -> float:
    """Mean number of distinct reversal runs (protocol positions) scored out of sample per case."""
    per_case = {}
    for key in keys:
        per_case.setdefault(key[1], set()).add(key[3])
    return _mean([len(v) for v in per_case.values()])


def compared_rows(table_rows: pd.DataFrame) -> pd.DataFrame:
    """The comparison rows of the claims table ``COMPARED`` names (``<prefix>-step``, ``-sin``, ``-pooled``)."""
    ids = table_rows["claim_id"].astype(str)
    keep = ids.map(lambda c: c.rsplit("-", 1)[0] in COMPARED and c.rsplit("-", 1)[-1] in ("step", "sin", "pooled"))
    return table_rows[keep]


# --------------------------------------------------------------------------- the power table


def power_table(runs: dict, case_dirs, table_rows: pd.DataFrame, protocols=REVERSAL_PROTOCOLS):
    """One row per comparison row of the table (``compared_rows``) and effect choice (``COLUMNS``), and the DEM cost.

    Parameters
    ----------
    runs : dict
        ``claims.inputs.runs`` of the comparison's curves (the transients scored per seed, per figure).
    case_dirs : list of path
        The DEM cases (stage sidecars: disks and CPU time).
    table_rows : DataFrame
        The claims table: each row's estimate (the measured effect), margin (the minimal one), s.d. and n.
    """
    cost = dem_cost(case_dirs, protocols)
    scored = {}
    for key, cur in runs.items():
        if not key[4] and "dem" in cur:
            scored.setdefault(table.kind_of(cur["dem"]), []).append(key)
    kinds = {"step": ("heaviside",), "sin": ("sinusoidal",), "pooled": ("heaviside", "sinusoidal")}
    rows = []
    for _, r in compared_rows(table_rows).iterrows():
        prefix, figure = str(r["claim_id"]).rsplit("-", 1)
        label, window = COMPARED[prefix]
        k0 = transients_per_seed([k for kind in kinds[figure] for k in scored.get(kind, [])])
        sd, n_now = float(r["sd"]), int(r["n"]) if np.isfinite(r["n"]) else 0
        effects = {"measured": float(r["estimate"]), "minimal": -float(r["margin"])}
        seed_cpu = cost["setup_cpu_s"] + len(protocols) * cost["transient_cpu_s"]   # a new seed runs every protocol
        for choice in EFFECTS:
            delta = effects[choice]
            n = seeds_needed(sd, delta)
            rows.append(dict(
                claim_id=r["claim_id"], quantity=label, window=window, effect_choice=choice, effect=delta,
                sd_per_seed=sd, seeds_measured=n_now, disks_per_seed=cost["disks"],
                transients_per_seed=k0, seeds_needed=n, transients=n * k0, particles=n * cost["disks"],
                core_hours=n * seed_cpu / 3600.0, power_measured=power_t(n_now, sd, delta)))
    return pd.DataFrame(rows, columns=COLUMNS), cost


def with_unknown_costs(power: pd.DataFrame, float_format: str = "%.6g") -> pd.DataFrame:
    """The power table as written to power.csv: a cost column's NaN (``COST_COLUMNS``) says ``UNKNOWN``.

    The numbers of those columns are formatted with ``float_format`` (the rest of the
    table keeps its types), so the file reads as before where the costs are known.
    """
    out = power.copy()
    for c in COST_COLUMNS:
        v = pd.to_numeric(out[c], errors="coerce")
        out[c] = [UNKNOWN if np.isnan(x) else float_format % x for x in v.to_numpy(float)]
    return out


# --------------------------------------------------------------------------- presets


def preset_from_config(name: str, path, cost: dict) -> dict:
    """Seeds (cases pooled across ensembles), disks and out-of-sample transients per case of a preset's YAML.

    Disks: the measured campaign's, scaled by the cell's area :math:`H^2\\,(W/H)`. Transients: every
    reversal protocol when the preset has two ensembles or more (a set per I scores the other I's runs),
    otherwise the protocols some calibration set leaves out (``heaviside_only`` scores the sinusoidal run).
    """
    try:
        cfg = yaml.safe_load(Path(path).read_text())
    except (OSError, yaml.YAMLError) as exc:
        raise ValueError(f"{path}: preset {name!r} not readable ({exc})") from None
    try:
        load = cfg["loading"]
        rates = load.get("inertial_numbers") or load.get("wall_velocities")
        ensembles = len(load["pressures"]) * len(rates)
        seeds = len(cfg["seeds"]) * ensembles
        protocols = list(cfg["protocols"])
        cell = cfg["cell"]
    except (KeyError, TypeError) as exc:
        raise ValueError(f"{path}: preset {name!r} lacks {exc} (loading, seeds, protocols, cell)") from None
    if ensembles >= 2:
        k = len(protocols)
    else:
        sets = (cfg.get("calibration") or {}).get("sets") or {}
        k = sum(any(p not in (s or {}).get("protocols", protocols) for s in sets.values()) for p in protocols)
    g = cost.get("geometry") or {}
    area0 = g.get("H_over_d", math.nan) ** 2 * g.get("W_over_H", 4)
    disks = cost["disks"] * cell["H_over_d"] ** 2 * cell.get("W_over_H", 4) / area0
    return {"name": name, "seeds": seeds, "disks": float(disks), "transients": float(k)}


def reach(row, seeds: int, disks: float, transients: float) -> dict:
    """Whether ``seeds`` cases of ``disks`` disks and ``transients`` scored transients each reach 80 % power."""
    sd = scaled_sd(row["sd_per_seed"], row["disks_per_seed"], row["transients_per_seed"], disks, transients) \
        if transients > 0 else math.nan
    n = seeds_needed(sd, row["effect"])
    return {"seeds_needed": n, "power": power_t(seeds, sd, row["effect"]), "reached": bool(seeds >= n)}


def campaign_preset(power: pd.DataFrame) -> dict:
    """The measured campaign itself as a preset."""
    r = power.iloc[0]
    return {"name": "measured (this campaign)", "seeds": int(r["seeds_measured"]), "disks": r["disks_per_seed"],
            "transients": r["transients_per_seed"]}

