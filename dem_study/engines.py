r"""The two DEM engines side by side: do YADE and LAMMPS give the same physics (issue 36)?

Reads each engine's finished cases, ``<case>/preshear.csv`` with its sidecar
``preshear.json``, ``pack.json`` and the reversal stage's ``<stage>.csv`` and
``<stage>.json`` (a campaign's ``<results_dir>/dem/``), or a data release
(``data/<name>/`` or its ``cases/``: checked against its manifest and restored,
``dem_contract.release``). Each engine is one *cell* of the bulk-vs-walls study
(``dem_study.bulk``: ``load_case``, ``cell_table``, ``comparison``), the first
engine (YADE) its reference, so the statistics are that study's:

- steady :math:`q \in` (mu, |A|, theta_A, phi, Z) over the last half of the
  pre-shear's strain path (``dem_contract.steady_values``; ``steady_window`` a
  strain instead): per engine the seed mean :math:`\bar x` and its standard error
  :math:`SE = s/\sqrt n` (theta_A on the circle of axial angles,
  ``analysis.mean_and_se``), the difference :math:`d = \bar x_L - \bar x_Y`
  (modulo 180 deg for theta_A) and

  .. math:: z = \frac{d}{\sqrt{SE_Y^2 + SE_L^2}};

  a quantity agrees when :math:`|z| \le k` (``match_se`` k = 2, ``bulk.comparison``'s
  rule), and at the family level when :math:`|z| \le z_F = \Phi^{-1}(1 - \alpha/(2m))`,
  Bonferroni's bound over the :math:`m = 5` steady quantities at family-wise
  :math:`\alpha = 0.05`: :math:`z_F = 2.58` (``family_z``);
- the early transient, :math:`q \in` (mu, |A|, theta_A) against the strain since
  the reversal over its first ``early_strain`` (0.1) in bins (``analysis.transient_curves``):
  the RMS difference of the two engines' seed-mean curves over the bins :math:`b`,
  :math:`\sqrt{\langle (\bar x_{L,b} - \bar x_{Y,b})^2 \rangle}`, against the RMS
  seed noise :math:`\sqrt{\langle SE_{L,b}^2 + SE_{Y,b}^2 \rangle}`; it agrees when
  the RMS is at most k times the noise (``bulk.comparison``). Beside it the mean
  difference over the bins, :math:`\langle \bar x_{L,b} - \bar x_{Y,b} \rangle`
  (an offset, against a difference of shape).

A stage with several reversals (a train) gives each seed the mean of its
transients, each mirrored into the frame of a reversal against the pre-shear
(``bulk.load_case``); the seed stays the unit of every standard error.

Cost per engine, from the sidecars (``dem_contract.stage_costs``): core-hours per
seed, the mean over seeds of :math:`\sum_j t_j / 3600` over the pack, pre-shear
and reversal stages :math:`j` (CPU seconds :math:`t_j`, ``cpu_time_s``), and the
throughput of the shear stages (pre-shear and reversal), summed over the seeds,

.. math:: P = \frac{N \sum_j n_j}{\sum_j t_j} \quad \text{particle-steps per CPU second}

(:math:`n_j` the stage's ``steps``, N the disks).

Every case of one engine must share one setting: its scene but the seed and the
keys that do not change the physics (``IGNORED``); the settings the two engines
differ in are reported (``scene_differences``), not refused.
"""
from __future__ import annotations

import fnmatch
import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.stats import norm

from dem_contract import DEMInputError, angle_difference, read_sidecar, sidecar_engine, stage_costs
from dem_contract.release import CASES_DIR, MANIFEST, read_manifest, require_intact, restore_case

from . import bulk
from .analysis import StudyInputError

#: The engines, the first the reference (YADE: yade_scripts/).
ENGINES = ("yade", "lammps")
#: Family-wise error rate of the steady quantities' family test.
FAMILY_ALPHA = 0.05
#: Scene keys that are not the physics: the seed, labels, run-time intervals, the guards, the engine.
IGNORED = ("seed", "meta", "run", "guards", "engine")


def family_z(m: int = len(bulk.STEADY), alpha: float = FAMILY_ALPHA) -> float:
    r"""Bonferroni's two-sided bound for m tests at family-wise ``alpha``: :math:`\Phi^{-1}(1 - \alpha/(2m))`."""
    return float(norm.isf(alpha / (2 * m)))


def is_release(folder) -> bool:
    """A data release (its folder, with ``manifest.yaml``) rather than a folder of case folders."""
    return (Path(folder) / MANIFEST).is_file()


def release_root(folder) -> Path | None:
    """The release a folder names: the release itself, or its ``cases/``; None for a folder of cases."""
    folder = Path(folder)
    if is_release(folder):
        return folder
    if folder.name == CASES_DIR and is_release(folder.parent):
        return folder.parent
    return None


def case_dirs(folder, stage: str, pattern: str = "*", scratch=None) -> list[Path]:
    """The finished cases under ``folder`` that hold ``stage``, their names matching ``pattern`` (fnmatch).

    A folder of cases: every sub-folder with ``preshear.csv`` and ``<stage>.csv``. A data release
    (``release_root``): every released case holding ``stage``, restored into ``scratch/<case>/``
    after the release is checked against its manifest (``dem_contract.release.require_intact``).

    Raises
    ------
    StudyInputError
        No such folder, a release without a scratch folder, or no finished case with ``stage``.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise StudyInputError(f"{folder}: folder of DEM cases not found")
    root = release_root(folder)
    if root is not None:
        if scratch is None:
            raise StudyInputError(f"{folder}: a data release needs a scratch folder to restore its cases into")
        require_intact(root)
        labels = [label for label, case in read_manifest(root)["cases"].items()
                  if stage in case.get("protocols", []) and fnmatch.fnmatch(label, pattern)]
        found = [restore_case(root, label, Path(scratch) / label) for label in sorted(labels)]
    else:
        found = sorted(d for d in folder.iterdir() if d.is_dir() and fnmatch.fnmatch(d.name, pattern)
                       and (d / "preshear.csv").is_file() and (d / f"{stage}.csv").is_file())
    if not found:
        raise StudyInputError(f"{folder}: no finished case with a pre-shear and a {stage} run"
                              + (f" matching {pattern!r}" if pattern != "*" else ""))
    return found


def flat(d: dict, prefix: str = "") -> dict:
    """A nested mapping as one level of dotted keys: ``{"a": {"b": 1}}`` -> ``{"a.b": 1}``."""
    out = {}
    for k, v in d.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict) and v:
            out.update(flat(v, key + "."))
        else:
            out[key] = v
    return out


def setting(scene: dict) -> dict:
    """The scene's physics and protocol as dotted keys: every key but ``IGNORED``."""
    return {k: v for k, v in flat(scene).items() if k.split(".")[0] not in IGNORED}


def case_scene(case_dir) -> dict:
    """The scene of a case as its pre-shear ran it (the sidecar's ``scene``, defaults filled)."""
    side = read_sidecar(Path(case_dir) / "preshear.csv")
    if not isinstance(side.get("scene"), dict):
        raise StudyInputError(f"{Path(case_dir) / 'preshear.json'}: sidecar without the scene it ran")
    return side["scene"]


def scene_differences(a: dict, b: dict) -> list[str]:
    """The keys of two settings (``setting``) whose values differ, as ``key: a -> b``, sorted."""
    keys = sorted(set(a) | set(b))
    return [f"{k}: {a.get(k, '(absent)')!r} -> {b.get(k, '(absent)')!r}" for k in keys if a.get(k) != b.get(k)]


def one_setting(engine: str, dirs) -> dict:
    """The setting all of an engine's cases share; ``StudyInputError`` naming the keys where they differ."""
    settings = [setting(case_scene(d)) for d in dirs]
    for d, s in zip(dirs[1:], settings[1:]):
        diff = scene_differences(settings[0], s)
        if diff:
            raise StudyInputError(f"{engine}: cases {Path(dirs[0]).name} and {Path(d).name} differ in "
                                  f"{'; '.join(diff)}: choose one setting (--{engine}-cases GLOB)")
    return settings[0]


def cases_table(engines: dict) -> pd.DataFrame:
    """One row per case: ``case`` (``<engine>/<folder>``), ``cell`` (the engine), ``label``, ``seed``, the
    cell's ``kind``, ``H_over_d``, ``W_over_d`` and ``dir``, the engines in the order of ``engines``."""
    rows = []
    for engine, dirs in engines.items():
        for d in dirs:
            scene = case_scene(d)
            H = float(scene.get("geometry", {}).get("H_over_d", math.nan))
            W = H * float(scene.get("geometry", {}).get("W_over_H", math.nan))
            rows.append(dict(case=f"{engine}/{Path(d).name}", cell=engine, label=Path(d).name, seed=scene.get("seed"),
                             kind=scene.get("cell", {}).get("kind", "walls"), H_over_d=H, W_over_d=W, dir=str(d)))
    return pd.DataFrame(rows)


def throughput(case_dir, stage: str) -> dict:
    """N, shear steps and CPU seconds of a case's pre-shear and reversal (``stage_costs``), and the
    engine that wrote its sidecar (``dem_contract.sidecar_engine``)."""
    try:
        c = stage_costs(case_dir, ("preshear", stage), keys=("steps", "cpu_time_s"), missing="raise")
    except DEMInputError as exc:
        raise StudyInputError(str(exc)) from None
    side = read_sidecar(Path(case_dir) / "preshear.csv")
    return {"N": c["N"], "steps": c["steps"], "cpu_time_s": c["cpu_time_s"],
            "engine_recorded": sidecar_engine(side)}


def cost_table(cases: pd.DataFrame, cells: pd.DataFrame, stage: str) -> pd.DataFrame:
    """Per engine: seeds, N, the engine its sidecars record, core-hours per seed (``bulk.cell_table``)
    and particle-steps per CPU second of the shear stages (module docstring)."""
    rows = []
    for engine, group in cases.groupby("cell", sort=False):
        t = [throughput(d, stage) for d in group["dir"]]
        cell = cells.set_index("cell").loc[engine]
        rows.append(dict(engine=engine, engine_recorded=", ".join(sorted({x["engine_recorded"] for x in t})),
                         seeds=len(t), N=int(cell["N"]), core_hours_per_seed=float(cell["core_hours_per_seed"]),
                         core_hours_pack_per_seed=float(cell["core_hours_pack_per_seed"]),
                         core_hours_preshear_per_seed=float(cell["core_hours_preshear_per_seed"]),
                         core_hours_reversal_per_seed=float(cell["core_hours_reversal_per_seed"]),
                         shear_steps_per_seed=float(np.mean([x["steps"] for x in t])),
                         particle_steps_per_cpu_s=float(sum(x["N"] * x["steps"] for x in t)
                                                        / sum(x["cpu_time_s"] for x in t))))
    out = pd.DataFrame(rows)
    out["throughput_ratio"] = out["particle_steps_per_cpu_s"] / out["particle_steps_per_cpu_s"].iloc[0]
    return out


def transient_length(case_dir, stage: str) -> float:
    r"""The shortest transient of a case's reversal run, in strain, from its sidecar:
    :math:`\min_k |\gamma_{k+1} - \gamma_k|` over the reversals' strains :math:`\gamma_k`
    (``reversals``, or ``reversal_strain``) with :math:`\gamma_{K+1}` the run's ``strain_end``."""
    side = read_sidecar(Path(case_dir) / f"{stage}.csv")
    starts = ([float(r["strain"]) for r in side["reversals"]] if side.get("reversals")
              else [float(side.get("reversal_strain", side.get("strain_start", math.nan)))])
    ends = [*starts[1:], float(side.get("strain_end", math.nan))]
    return min(abs(e - s) for s, e in zip(starts, ends))


def early(curves: dict, early_strain: float) -> dict:
    """Each seed-mean curve cut to its bins whose centre lies before ``early_strain``."""
    return {c: df[df["strain_since_reversal"] < early_strain].reset_index(drop=True) for c, df in curves.items()}


def compare(cases: pd.DataFrame, stage: str, edges: np.ndarray, early_strain: float,
            steady_window: float | None = None, match_se: float = 2.0):
    """Every case loaded (``bulk.load_case``), each engine a cell (``bulk.cell_table``), the others set
    against the first engine over the early transient (``bulk.comparison``).

    Returns
    -------
    tuple
        (comparison table of ``bulk.comparison``, cell table, seed-mean curves on ``edges``).
    """
    results = {c: bulk.load_case(d, c, steady_window, edges, stage) for c, d in zip(cases["case"], cases["dir"])}
    cells, curves = bulk.cell_table(cases, results, early_strain)
    reference = cells["cell"].iloc[0]
    pairs = bulk.comparison(cells, early(curves, early_strain), [reference], reference, match_se)
    return pairs, cells, curves


def agreement_table(pairs: pd.DataFrame, curves: dict, early_strain: float, match_se: float = 2.0) -> pd.DataFrame:
    """One row per quantity: the steady ones (per engine mean, SE and seeds; difference, z, agreement
    at ``match_se`` and at the family level ``family_z``) and the early transients (RMS difference,
    RMS seed noise, their ratio, mean difference over the bins, agreement). Module docstring."""
    by_cell = pairs.set_index("cell")
    reference = pairs.loc[pairs["reference"].fillna("") == "", "cell"].iloc[0]
    ref = by_cell.loc[reference]
    zf = family_z()
    cut = early(curves, early_strain)
    rows = []
    for other, row in by_cell.drop(index=reference).iterrows():
        for q in bulk.STEADY:
            z = float(row[f"z_{q}"])
            rows.append({"quantity": q, "kind": "steady", "window": "last half of the pre-shear",
                         f"{reference}_mean": ref[q], f"{reference}_se": ref[f"{q}_se"],
                         f"{reference}_seeds": int(ref["seeds"]),
                         f"{other}_mean": row[q], f"{other}_se": row[f"{q}_se"], f"{other}_seeds": int(row["seeds"]),
                         "difference": float(row[f"d_{q}"]), "z": z,
                         "agrees": bool(abs(z) <= match_se), "agrees_family": bool(abs(z) <= zf)})
        for q in bulk.TRANSIENT:
            rms, noise = float(row[f"transient_{q}_rms"]), float(row[f"transient_{q}_noise"])
            d = (angle_difference(cut[other][q].to_numpy(), cut[reference][q].to_numpy()) if q in bulk.AXIAL
                 else cut[other][q].to_numpy() - cut[reference][q].to_numpy())
            rows.append({"quantity": q, "kind": "transient", "window": f"first {early_strain:g} after the reversal",
                         f"{reference}_seeds": int(ref["seeds"]), f"{other}_seeds": int(row["seeds"]),
                         "difference": float(np.mean(d)), "rms_difference": rms, "rms_noise": noise,
                         "noise_ratio": rms / noise if noise > 0 else math.nan,
                         "agrees": bool(rms <= match_se * noise)})
    return pd.DataFrame(rows)


def summary(table: pd.DataFrame, cost: pd.DataFrame, stage: str, settings: dict, early_strain: float,
            steady_window: float | None, match_se: float) -> dict:
    """The run's settings, the rule, the scene differences between the engines and what agrees."""
    names = list(settings)
    return {"stage": stage, "engines": names, "reference": names[0],
            "steady_window": "last half" if steady_window is None else steady_window,
            "early_strain": early_strain, "match_se": match_se, "family_z": family_z(),
            "family_alpha": FAMILY_ALPHA, "family_size": len(bulk.STEADY),
            "scene_differences": scene_differences(settings[names[0]], settings[names[1]]),
            "agree": [f"{k} {q}" for k, q, a in zip(table["kind"], table["quantity"], table["agrees"]) if a],
            "differ": [f"{k} {q}" for k, q, a in zip(table["kind"], table["quantity"], table["agrees"]) if not a],
            "cost": cost.to_dict("records")}


def _fmt(x, digits=4) -> str:
    return "-" if x is None or (isinstance(x, float) and not np.isfinite(x)) else f"{x:.{digits}g}"


def markdown(table: pd.DataFrame, cost: pd.DataFrame, info: dict) -> str:
    """The agreement as markdown: the steady table, the transient table and the cost table."""
    ref, other = info["engines"]
    rule = (f"agrees: |z| <= {info['match_se']:g} (family: |z| <= {info['family_z']:.2f}, Bonferroni over "
            f"{info['family_size']} steady quantities at {info['family_alpha']:.0%})")
    window = info["steady_window"] if isinstance(info["steady_window"], str) else f"last {info['steady_window']:g}"
    lines = [f"Stage `{info['stage']}`; {ref} (reference) against {other}; steady values over the {window}"
             f" of the pre-shear; seed mean +- standard error; d = {other} - {ref}, z = d / sqrt(SE1^2 + SE2^2); "
             f"{rule}.", "",
             f"| quantity | {ref} | {other} | seeds | difference | z | agrees | agrees (family) |",
             "|---|---|---|---|---|---|---|---|"]
    for _, r in table[table["kind"] == "steady"].iterrows():
        lines.append(f"| {r['quantity']} | {_fmt(r[f'{ref}_mean'])} +- {_fmt(r[f'{ref}_se'], 2)} "
                     f"| {_fmt(r[f'{other}_mean'])} +- {_fmt(r[f'{other}_se'], 2)} "
                     f"| {r[f'{ref}_seeds']} + {r[f'{other}_seeds']} | {r['difference']:+.4g} | {r['z']:+.2f} "
                     f"| {'yes' if r['agrees'] else '**no**'} | {'yes' if r['agrees_family'] else '**no**'} |")
    lines += ["", f"Early transient, the first {info['early_strain']:g} strain after the reversal: RMS over the "
              f"bins of the seed-mean curves' difference against the RMS seed noise sqrt(<SE1^2 + SE2^2>); "
              f"agrees: RMS <= {info['match_se']:g} x noise; mean difference = <{other} - {ref}> over the bins.", "",
              "| quantity | RMS difference | RMS seed noise | ratio | mean difference | agrees |",
              "|---|---|---|---|---|---|"]
    for _, r in table[table["kind"] == "transient"].iterrows():
        lines.append(f"| {r['quantity']} | {_fmt(r['rms_difference'])} | {_fmt(r['rms_noise'])} "
                     f"| {r['noise_ratio']:.2f} | {r['difference']:+.4g} | {'yes' if r['agrees'] else '**no**'} |")
    lines += ["", "Cost, from the sidecars: core-hours per seed (pack + pre-shear + reversal CPU, each stage beside "
              "it) and particle-steps per CPU second of the shear stages (N x steps / CPU s).", "",
              "| engine | recorded | seeds | N | core-hours per seed | pack | pre-shear | reversal "
              "| particle-steps per CPU s | ratio |", "|---|---|---|---|---|---|---|---|---|---|"]
    for _, c in cost.iterrows():
        lines.append(f"| {c['engine']} | {c['engine_recorded']} | {c['seeds']} | {c['N']} "
                     f"| {c['core_hours_per_seed']:.4f} | {c['core_hours_pack_per_seed']:.4f} "
                     f"| {c['core_hours_preshear_per_seed']:.4f} "
                     f"| {c['core_hours_reversal_per_seed']:.4f} | {c['particle_steps_per_cpu_s']:.3g} "
                     f"| {c['throughput_ratio']:.2f} |")
    diff = info["scene_differences"]
    lines += ["", "Scene differences between the engines (seed, labels, run intervals and guards left out): "
              + ("; ".join(f"`{d}`" for d in diff) if diff else "none") + "."]
    return "\n".join(lines) + "\n"


def write(out, name: str, table: pd.DataFrame, cost: pd.DataFrame, info: dict) -> dict:
    """``<name>_agreement.csv``, ``<name>_agreement.md``, ``<name>_cost.csv``, ``<name>_agreement.json`` in ``out``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths = {"agreement_csv": out / f"{name}_agreement.csv", "agreement_md": out / f"{name}_agreement.md",
             "cost_csv": out / f"{name}_cost.csv", "agreement_json": out / f"{name}_agreement.json"}
    table.to_csv(paths["agreement_csv"], index=False, float_format="%.6g")
    cost.to_csv(paths["cost_csv"], index=False, float_format="%.6g")
    paths["agreement_md"].write_text(markdown(table, cost, info))
    paths["agreement_json"].write_text(json.dumps(info, indent=2, default=float) + "\n")
    return paths
