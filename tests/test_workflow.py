"""The Snakemake workflow: config validation, the DAG of each preset, the SLURM profile.

The DAGs run Snakemake itself (dry runs: no job executes); a bad config goes through the
pre-flight command the Snakefile's gate runs (``helpers.preflight_check``; its wiring into
Snakemake: tests/test_campaign_preflight.py).
"""
import shutil

import pytest
import yaml

from tests.helpers import ROOT, counts, preflight_check, yade_module


def write_config(tmp_path, preset, **changes):
    """A copy of a preset with nested keys changed, e.g. cell={"H_over_d": 1}."""
    config = yaml.safe_load((ROOT / "config" / f"{preset}.yaml").read_text())
    for key, value in changes.items():
        if isinstance(value, dict) and key in config:
            config[key].update(value)
        else:
            config[key] = value
    path = tmp_path / "config.yaml"
    path.write_text(yaml.safe_dump(config))
    return path


@pytest.mark.parametrize("preset", ["config", "quick", "ci"])
def test_every_preset_builds_a_dag(preset, shared_dry_run):
    result = shared_dry_run("--configfile", f"config/{preset}.yaml")
    assert result.returncode == 0, result.stderr[-3000:]
    assert "dem_preshear" in result.stdout


@pytest.mark.parametrize(
    "changes, key, allowed",
    [
        ({"cell": {"H_over_d": 1}}, "H_over_d", "minimum of 4"),
        ({"material": {"kappa": 1.0}}, "kappa", "minimum of 100"),
        ({"loading": {"pressures": [-5.0]}}, "pressures", "less than or equal to the minimum of 0"),
        ({"timestep": {"dt_over_tc": 0.9}}, "dt_over_tc", "maximum of 0.3"),
    ],
)
def test_bad_config_value_stops_before_any_job_naming_key_and_range(tmp_path, changes, key, allowed):
    config = write_config(tmp_path, "ci", **changes)
    result = preflight_check(config)
    assert result.returncode != 0
    assert key in result.stderr and allowed in result.stderr, result.stderr[-2000:]


def test_unknown_config_key_is_rejected(tmp_path):
    config = write_config(tmp_path, "ci", cel={"H_over_d": 8})
    result = preflight_check(config)
    assert result.returncode != 0
    assert "'cel'" in result.stderr


def test_one_preshear_feeds_every_reversal(shared_dry_run):
    result = shared_dry_run("--configfile", "config/ci.yaml", quiet=False)
    assert result.returncode == 0, result.stderr[-3000:]
    ci = yaml.safe_load((ROOT / "config" / "ci.yaml").read_text())
    n_cases = len(ci["seeds"]) * len(ci["loading"]["pressures"]) * len(ci["loading"]["inertial_numbers"])
    jobs = counts(result.stdout)
    assert jobs["dem_preshear"] == n_cases
    assert jobs["dem_reversal"] == n_cases * len(ci["protocols"])


@pytest.mark.skipif(shutil.which("sbatch") is not None, reason="a real cluster: do not touch it from tests")
def test_slurm_profile_plans_the_paper_campaign(shared_dry_run):
    result = shared_dry_run("--profile", "profiles/slurm", quiet=False)
    assert result.returncode == 0, result.stderr[-3000:]
    assert "dem_preshear" in result.stdout


# config section -> scene section, where the names differ
SCENE_SECTION = {"cell": "geometry"}


def test_config_schema_ranges_match_the_scene_validator():
    """The pipeline's schema and yade_scripts' own validator must accept the same values."""
    SPEC = yade_module("scene").SPEC
    schema = yaml.safe_load((ROOT / "workflow/schemas/config.schema.yaml").read_text())
    compared = 0
    for section, block in schema["properties"].items():
        scene_block = SPEC.get(SCENE_SECTION.get(section, section))
        if not scene_block or "properties" not in block:
            continue
        for key, rule in block["properties"].items():
            if key not in scene_block or rule.get("type") != "number":
                continue
            spec = scene_block[key][0]
            low = rule.get("minimum", rule.get("exclusiveMinimum"))
            high = rule.get("maximum", rule.get("exclusiveMaximum"))
            assert (low, "exclusiveMinimum" in rule) == (spec["lo"], spec["lo_open"]), f"{section}.{key} low"
            assert (high, "exclusiveMaximum" in rule) == (spec["hi"], spec["hi_open"]), f"{section}.{key} high"
            compared += 1
    assert compared >= 20


def test_every_rule_has_a_log_and_a_benchmark_and_the_study_reuses_the_dem_rules(workflow_dir):
    """Every rule that runs a job (all but the target rule `all`) keeps its log and its benchmark;
    the DEM study's stages are the campaign's rules (one YADE command, in dem.smk)."""
    from snakemake.api import SnakemakeApi
    from snakemake.settings.types import ConfigSettings, OutputSettings, ResourceSettings, StorageSettings

    with SnakemakeApi(OutputSettings()) as api:
        workflow = api.workflow(
            resource_settings=ResourceSettings(), storage_settings=StorageSettings(),
            config_settings=ConfigSettings(configfiles=[ROOT / "config" / "config.yaml"]),  # every rule in use
            snakefile=workflow_dir / "Snakefile", workdir=workflow_dir)
        rules = {rule.name: rule for rule in workflow._workflow.rules}
    assert {"scene", "dem_pack", "calibrate", "compare_predict", "dem_study_pack"} <= set(rules)
    missing = [name for name, rule in rules.items() if name != "all" and not (rule.log and rule.benchmark)]
    assert missing == []
    for campaign_rule, study_rule in [("dem_pack", "dem_study_pack"), ("dem_preshear", "dem_study_preshear"),
                                      ("dem_reversal", "dem_study_heaviside")]:
        assert rules[study_rule].shellcmd == rules[campaign_rule].shellcmd
    assert "run_stage.py" not in (ROOT / "workflow" / "rules" / "accuracy.smk").read_text()

