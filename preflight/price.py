"""The campaign's price, printed by the pre-flight check before any job (``campaign.price``).

The Snakefile prints it once the config has passed the check and the schema has filled its
defaults, on stderr (stdout may be a DAG or a job table), with Snakemake's ``--cores`` (``-j``);
``python -m preflight check FILE [--cores N]`` prints it after its "ok". The DEM studies the config
turns on (``accuracy.dem_study``, ``accuracy.bulk_vs_walls.run``) run in the same Snakemake: one
more line each, from their own estimates (the same cost model, each case one job).
"""
from __future__ import annotations

import sys

from campaign.price import ROOT, duration, plural, price, price_lines
from campaign.schedule import makespan
from dem_contract import DEMInputError

#: Cores assumed when Snakemake was given none (a dry run without -j) and by the CLI: `make quick` runs -j2.
DEFAULT_CORES = 2


def price_text(config: dict, cores: int | None = None, root=ROOT) -> str:
    """The price lines of ``config`` (validated, defaults filled) on ``cores``; one line saying why when it
    cannot be made (a release that cannot be read: the workflow names that itself)."""
    cores = cores or DEFAULT_CORES
    try:
        return "\n".join(price_lines(price(config, cores, root)) + study_lines(config, cores))
    except (OSError, DEMInputError) as exc:
        return f"price: not estimated ({exc})"


def study_lines(config: dict, cores: int) -> list[str]:
    """One line per DEM study the config runs: its cases, core-hours and wall time on ``cores``."""
    from dem_study import bulk_cells, grid

    accuracy = config.get("accuracy") or {}
    studies = [("the DEM resolution study (accuracy.dem_study)", "python -m dem_study estimate", grid.estimate)
               if accuracy.get("dem_study") else None,
               ("the bulk-vs-walls study (accuracy.bulk_vs_walls)", "python -m dem_study.bulk_cli estimate",
                bulk_cells.estimate) if bulk_cells.enabled(config) else None]
    out = []
    for name, command, estimate in filter(None, studies):
        seconds = estimate(config)["est_core_s"]
        out.append(f"price: and {name}: {plural(len(seconds), 'DEM case')}, {seconds.sum() / 3600:.2g} core-hours, "
                   f"about {duration(makespan(seconds, cores))} more on {plural(cores, 'core')} ({command})")
    return out


def print_price(config: dict, cores: int | None = None, file=None) -> None:
    """Print ``price_text`` on ``file`` (stderr by default)."""
    print(price_text(config, cores), file=file or sys.stderr, flush=True)


def workflow_cores(workflow) -> int | None:
    """Snakemake's ``--cores`` (``-j``), or None when it was given none (a dry run)."""
    from snakemake.exceptions import WorkflowError

    try:
        return workflow.cores
    except WorkflowError:
        return None
