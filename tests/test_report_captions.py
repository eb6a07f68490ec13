"""The Snakemake report carries the verdict: the claims, packing and calibration tables are in it
(as HTML, which the report shows inline; workflow/rules/report.smk), and every caption names the
preset and the cases it shows.

Captions (workflow/report/*.rst) are Jinja templates Snakemake renders with the job's config,
wildcards and params; here each is rendered the same way with every preset's own config
(its schema defaults filled as the Snakefile fills them).
"""
import copy
import re
from pathlib import Path
from types import SimpleNamespace

import pytest
import yaml
from jinja2 import Environment, StrictUndefined

from tests.helpers import ROOT, workflow_rules

CAPTIONS = sorted((ROOT / "workflow" / "report").glob("*.rst"))
#: Captions of rules that run only with a study switched on, and the config that switches it on.
STUDY_CAPTIONS = {"dem_cost": ["config"], "dem_transients": ["config"], "mu_of_I": ["config"],
                  "dem_repeats": ["config"], "bulk_vs_walls": ["quick", "bulk_validation"]}
PRESETS = ["ci", "quick", "bulk", "config"]


def preset_config(*names):
    """The presets' files merged as ``--configfile a b`` merges them, with the schema's defaults."""
    from snakemake.utils import update_config, validate
    config = {}
    for name in names:
        update_config(config, yaml.safe_load((ROOT / "config" / f"{name}.yaml").read_text()))
    validate(config, str(ROOT / "workflow" / "schemas" / "config.schema.yaml"))
    return config


def render(caption: Path, config: dict) -> str:
    env = Environment(trim_blocks=True, lstrip_blocks=True, undefined=StrictUndefined)  # Snakemake's, but strict
    snakemake = SimpleNamespace(config=copy.deepcopy(config), wildcards=SimpleNamespace(calset="all"),
                                params=SimpleNamespace(dirs=["a", "b", "c"], protocols=["heaviside"]))
    return env.from_string(caption.read_text()).render(snakemake=snakemake, categories={}, files={})


@pytest.mark.parametrize("caption", CAPTIONS, ids=[c.stem for c in CAPTIONS])
def test_every_caption_names_its_preset_in_every_preset_that_makes_it(caption):
    for names in ([STUDY_CAPTIONS[caption.stem]] if caption.stem in STUDY_CAPTIONS else [[p] for p in PRESETS]):
        config = preset_config(*names)
        text = render(caption, config)
        assert f"``{config['campaign']}``" in text, (caption.name, names, text[-500:])
        assert "{{" not in text and "{%" not in text


def test_a_campaign_caption_lists_the_cases_and_a_set_caption_its_set():
    config = preset_config("quick")
    text = render(ROOT / "workflow" / "report" / "fig4_heaviside.rst", config)
    assert "I = 0.002, 0.005" in text and "seeds 1, 2, 3" in text and "protocols heaviside, sinusoidal" in text
    assert "``all``" in text and "made from 3 DEM cases" in text


@pytest.fixture(scope="module")
def report_flags(module_workflow_dir):
    """Output path (below the results folder) -> its report flag, for every rule of the quick preset."""
    rules = workflow_rules(module_workflow_dir, module_workflow_dir / "config" / "quick.yaml")
    return {re.sub(r"\{(\w+),[^}]*\}", r"{\1}", str(f).split("results/", 1)[-1]): f.flags.get("report")
            for rule in rules for f in rule.output}


#: The report shows HTML and images inline and offers a CSV for download: each verdict table is in it as both.
@pytest.mark.parametrize("table", ["claims/paper_claims.csv", "claims/paper_claims.html", "claims/paper_claims.png",
                                   "accuracy/packing_cost.csv", "accuracy/packing_cost.html",
                                   "calibration/{calset}/params_table.csv", "calibration/{calset}/params_table.html",
                                   "calibration/{calset}/fit_quality.csv", "calibration/{calset}/fit_quality.html"])
def test_the_verdict_tables_are_in_the_report(table, report_flags):
    assert report_flags.get(table), (table, sorted(k for k, v in report_flags.items() if v))
