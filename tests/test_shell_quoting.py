"""No config value reaches a shell as code: every placeholder of every rule's shell command is quoted.

The workflow is loaded through Snakemake's API (no job runs) with the presets that between
them define every rule, the release rules included (they exist only when a release is
named), and every ``{placeholder}`` of every shell command must carry Snakemake's ``:q``
(``shlex.quote`` of each word; a list gives one quoted argument per item, an empty value
nothing). A results folder, a release path or a word of ``calibration.options`` then
reaches its program as one argument, whatever it holds. Quoting every placeholder, not only
those known to come from the config, keeps the rule checkable without tracing where each
value comes from.
"""
import re
import string

import pytest

from tests.helpers import ROOT, workflow_rules

#: (config files, --config values) whose rules, together, are every rule of the workflow.
LOADS = [
    (["config/bulk_decide.yaml"], {}),                                  # release_case
    (["config/bulk.yaml", "config/bulk_validation_paper.yaml"],         # release_bulk_case
     {"release": "data/bulk-validation-paper"}),
]


def unquoted_placeholders(command: str) -> list[str]:
    """The placeholders of a shell command template without Snakemake's ``:q`` (``{{`` is a brace, not one)."""
    return [f"{{{field}{':' + spec if spec else ''}}}"
            for _, field, spec, _ in string.Formatter().parse(command)
            if field is not None and not (spec or "").endswith("q")]


@pytest.fixture(scope="module")
def rules(module_workflow_dir):
    """Every rule of the workflow, by name (the union of the LOADS)."""
    out = {}
    for files, config in LOADS:
        for rule in workflow_rules(module_workflow_dir, *(module_workflow_dir / f for f in files), config=config):
            out.setdefault(rule.name, rule)
    return out


def test_the_scan_sees_every_rule_of_the_rule_files(rules):
    texts = [ROOT / "Snakefile", *sorted((ROOT / "workflow" / "rules").glob("*.smk"))]
    named = {name for path in texts for name in re.findall(r"^\s*rule\s+(\w+)\s*:", path.read_text(), re.M)}
    assert named and named <= set(rules), sorted(named - set(rules))
    assert {"release_case", "release_bulk_case", "dem_pack", "bulk_study_pack"} <= set(rules)


def test_the_scan_finds_a_placeholder_without_q():
    assert unquoted_placeholders("{PY} -m x --out {params.out:q} {{ {log} }} {x:>3}") == ["{PY}", "{log}", "{x:>3}"]
    assert unquoted_placeholders("echo {{literal}} {output:q}") == []


def test_every_placeholder_of_every_shell_command_is_quoted(rules):
    shell_rules = {name: rule.shellcmd for name, rule in rules.items() if rule.shellcmd}
    assert len(shell_rules) > 20, sorted(shell_rules)
    bad = {name: unquoted_placeholders(cmd) for name, cmd in shell_rules.items() if unquoted_placeholders(cmd)}
    assert not bad, bad


@pytest.mark.parametrize("rule_name, key", [("calibrate", "calibration.options"),
                                           ("compare_predict", "compare.options")])
def test_every_option_a_rule_passes_is_refused_in_its_options_string(rules, rule_name, key):
    from preflight.options import OWNED

    passed = set(re.findall(r"(?<![\w-])--[a-z][\w-]*", rules[rule_name].shellcmd))
    owned = set(OWNED[key][1])
    assert {"--dem", "--protocols", "--out"} <= passed <= owned, sorted(passed - owned)
