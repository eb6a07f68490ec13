"""The campaign's price, printed by the pre-flight check before any job (``campaign.price``).

The Snakefile prints it once the config has passed the check and the schema has filled its
defaults, on stderr (stdout may be a DAG or a job table), with Snakemake's ``--cores`` (``-j``);
``python -m preflight check FILE [--cores N]`` prints it after its "ok".
"""
from __future__ import annotations

import sys

from campaign.price import ROOT, price, price_lines
from dem_contract import DEMInputError

#: Cores assumed when Snakemake was given none (a dry run without -j) and by the CLI: `make quick` runs -j2.
DEFAULT_CORES = 2


def price_text(config: dict, cores: int | None = None, root=ROOT) -> str:
    """The price lines of ``config`` (validated, defaults filled) on ``cores``; one line saying why when it
    cannot be made (a release that cannot be read: the workflow names that itself)."""
    try:
        return "\n".join(price_lines(price(config, cores or DEFAULT_CORES, root)))
    except (OSError, DEMInputError) as exc:
        return f"price: not estimated ({exc})"


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
