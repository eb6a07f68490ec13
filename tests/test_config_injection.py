"""A config file is data: no value in it runs as a command (issue 33, item 1).

Each injection the issue demonstrated goes through the real ``snakemake`` in a working copy
of its own. Before the fix each ran the command in the value (``touch ./PWNED``, a file in
the working copy) or, for the options string, let the whole dry run through with exit 0;
now the pre-flight refuses the config with exit code 2 before Snakemake plans any job,
naming the key. Where the injected command would run within seconds (a results folder's
first job, a release's restore), the run is a real one, not a dry run, so that a command
that slipped through would leave its file behind.
"""
import yaml

from tests.helpers import ROOT, snakemake, workflow_copy

CI = yaml.safe_load((ROOT / "config" / "ci.yaml").read_text())


def assert_refused_before_any_job(result, workdir, key):
    """Exit 2 from the pre-flight naming ``key``: no DAG, no job, no file made by the value."""
    message = result.stdout + result.stderr
    assert result.returncode == 2, message[-3000:]
    assert "Building DAG" not in message and "Traceback" not in message, message[-3000:]
    assert f"config error: {key}" in message, message[-3000:]
    assert not (workdir / "PWNED").exists()


def test_calibration_options_with_a_command_substitution_are_refused_before_any_job(tmp_path):
    config = dict(CI, calibration=dict(CI["calibration"], options=CI["calibration"]["options"]
                                       + " --route2-method=LSODA$(touch$IFS./PWNED)"))
    path = tmp_path / "config.yaml"
    path.write_text(yaml.safe_dump(config))
    workdir = workflow_copy(tmp_path / "workflow")
    result = snakemake("-n", "--configfile", path, cwd=workdir)
    assert_refused_before_any_job(result, workdir, "calibration.options")
    assert "no quote, $, backtick" in result.stderr


def test_results_dir_with_a_backtick_is_refused_before_any_job(tmp_path):
    workdir = workflow_copy(tmp_path / "workflow")
    results = "r`touch$IFS./PWNED`"
    result = snakemake("-j1", "--configfile", "config/ci.yaml", "--config", f"results_dir={results}",
                       "--", f"{results}/accuracy/ode_work_precision.csv", cwd=workdir)
    assert_refused_before_any_job(result, workdir, "results_dir")
    assert "letters, digits and . _ - /" in result.stderr


def test_release_path_with_a_backtick_is_refused_before_any_job(tmp_path):
    """A copy of data/bulk-decide (a link to it) in a folder whose name holds a command, named by ``release:``."""
    workdir = workflow_copy(tmp_path / "workflow")
    release = tmp_path / "rel`touch$IFS./PWNED`"
    release.parent.mkdir()
    release.symlink_to(ROOT / "data" / "bulk-decide")
    result = snakemake("-j1", "--configfile", "config/bulk_decide.yaml",
                       "--config", "results_dir=results-x", f"release={release}",
                       "--", "results-x/dem/p100000_I0.001_s1/scene.json", cwd=workdir)
    assert_refused_before_any_job(result, workdir, "release")
