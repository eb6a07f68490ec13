"""docs/outputs.md kept true: every file its "made by" column names exists, and every figure it names
is an output of the rule it names (the rules as the workflow parses them, every study switched on)."""
import re
from pathlib import Path

import pytest

from tests.helpers import ROOT, workflow_rules

OUTPUTS = ROOT / "docs" / "outputs.md"
HEADER = ["file", "rule", "made by", "caption", "in"]
#: Every preset's rules at once: the paper preset with its opt-in studies and benchmarks on.
ALL_ON = {"accuracy": {"dem_study": True, "batched_cost": True, "calibration_cost": True,
                       "bulk_vs_walls": {"run": True}}}


def rows() -> list[dict]:
    """The rows of every table of docs/outputs.md with the columns ``HEADER``, as column -> cell text."""
    out, header = [], None
    for line in OUTPUTS.read_text().splitlines():
        if not line.startswith("|"):
            header = None
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if header is None:
            header = cells
        elif set(line) - set("|- ") and header == HEADER:
            out.append(dict(zip(header, cells)))
    return out


def quoted(cell: str) -> list[str]:
    """The words of a cell between backticks."""
    return re.findall(r"`([^`]+)`", cell)


def figures(cell: str) -> list[str]:
    """The PNG files a "file" cell names: ``a.{csv,png}`` -> a.png, and ``a.csv``, ``.png`` -> a.png."""
    names, stem = [], ""
    for word in quoted(cell):
        word = Path(word).name
        if word.startswith("."):
            word = stem + word
        stem = word.split(".", 1)[0]
        brace = re.fullmatch(r"(.*)\.\{(.*)\}", word)
        names += [f"{brace[1]}.{ext}" for ext in brace[2].split(",")] if brace else [word]
    return [n for n in names if n.endswith(".png")]


def test_the_table_has_rows_and_every_made_by_path_exists():
    table = rows()
    assert len(table) > 30
    paths = [w for r in table for w in quoted(r["made by"]) if "/" in w]
    assert paths
    assert [p for p in paths if not (ROOT / p).exists()] == []


@pytest.fixture(scope="module")
def rule_outputs(module_workflow_dir):
    rules = workflow_rules(module_workflow_dir, module_workflow_dir / "config" / "config.yaml",
                           module_workflow_dir / "config" / "bulk_validation.yaml", config=ALL_ON)
    return {r.name: {Path(str(f)).name for f in r.output} for r in rules}


def test_every_figure_named_is_an_output_of_the_rule_named(rule_outputs):
    named = [(fig, quoted(r["rule"])) for r in rows() for fig in figures(r["file"])]
    assert len(named) >= 12
    unknown = sorted({rule for _, names in named for rule in names} - set(rule_outputs))
    assert unknown == []
    assert [(fig, names) for fig, names in named
            if not any(fig in rule_outputs[rule] for rule in names)] == []
