"""Bad config is stopped before any job, by the schema and preflight/checks.py, naming the key.

Every case is a copy of the CI preset with one thing wrong. Each goes through the
pre-flight's own command (``python -m preflight check FILE``, called in-process:
the Snakefile's gate runs the same ``preflight.check``); a case passes when it
exits with code 2 and its message names the key (and, where given, the allowed
value). A few representative cases (``END_TO_END``: a schema range, a cross-key
check, a duplicated key with its lines, a calibrate option, a results folder) also
run the real ``snakemake --dry-run`` (about 2.7 s of CPU each), which must exit
with code 2, plan no job, and print the very lines the command printed.
"""
import copy
import math
import shutil
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
import yaml

import preflight
from tests.helpers import ROOT, preflight_check, snakemake, workflow_copy

CI = yaml.safe_load((ROOT / "config" / "ci.yaml").read_text())
# without extra calibrate options: checking them imports calibrate (seconds), needed only by their own cases
CI["calibration"]["options"] = ""


def edited(**sections):
    """The CI preset with sections updated (a dict updates the section, anything else replaces it)."""
    def edit(config):
        for key, value in sections.items():
            if isinstance(value, dict) and isinstance(config.get(key), dict):
                config[key].update(value)
            else:
                config[key] = value
    return edit


def replaced(**sections):
    """The CI preset with whole sections replaced."""
    def edit(config):
        config.update(copy.deepcopy(sections))
    return edit


CI_TEXT = (ROOT / "config" / "ci.yaml").read_text()

# name -> (edit of the CI config, or the config file's text; words the message must hold)
CASES = {
    "nan_pressure": (edited(loading={"pressures": [math.nan]}), ["loading.pressures[0]", "finite"]),
    "nan_kappa": (edited(material={"kappa": math.nan}), ["material.kappa", "finite"]),
    "nan_preshear_strain": (edited(preshear={"strain": math.nan}), ["preshear.strain", "finite"]),
    "nan_protocol_strain": (edited(protocols={"heaviside": {"strain": math.nan}}),
                            ["protocols.heaviside.strain", "finite"]),
    "wall_velocity_gives_I_0.32": (replaced(loading={"pressures": [1e5], "wall_velocities": [10.0]}),
                                   ["loading.wall_velocities[0]", "I = 0.316", "[1e-05, 0.1]"]),
    "wall_velocity_above_quasi_static": (replaced(loading={"pressures": [1e5], "wall_velocities": [0.5]}),
                                         ["loading.wall_velocities[0]", "I = 0.0158", "allow_inertial"]),
    "inertial_number_above_quasi_static": (replaced(loading={"pressures": [1e5], "inertial_numbers": [0.05]}),
                                           ["loading.inertial_numbers[0]", "allow_inertial"]),
    "fine_interval_above_coarse": (edited(sampling={"fine_interval": 0.01, "coarse_interval": 0.005}),
                                   ["sampling.fine_interval", "coarse_interval"]),
    "bulk_exclusion_fills_the_gap": (edited(sampling={"bulk_exclusion_d": 5}),
                                     ["sampling.bulk_exclusion_d", "cell.H_over_d", "<= 4.5"]),
    "loose_packing_denser_than_guess": (edited(pack={"initial_solid_fraction": 0.7, "solid_fraction_guess": 0.6}),
                                        ["pack.initial_solid_fraction", "< 0.6"]),
    "float_seed": (edited(seeds=[1.0]), ["seeds[0]", "integer"]),
    "periodic_cell_too_wide": (edited(cell={"kind": "periodic", "W_over_H": 4}),
                               ["cell.W_over_H", "W_over_H <= 1.1", "periodic"]),
    "cell_mass_for_a_wall_cell": (edited(cell={"mass": 0.5}), ["cell.mass", "periodic"]),
    "viscel_law_in_a_periodic_cell": (lambda c: (edited(cell={"kind": "periodic", "W_over_H": 1.0},
                                                        material={"contact_law": "viscel"})(c),
                                                 c["sampling"].pop("bulk_exclusion_d")),  # a wall cell's key
                                      ["material.contact_law", "viscel", "periodic"]),
    "pressures_share_a_label": (edited(loading={"pressures": [100000.0, 100000.1]}),
                                ["loading.pressures", "p100000_I0.01_s1"]),
    "inertial_numbers_share_a_label": (replaced(loading={"pressures": [1e5], "inertial_numbers": [0.002, 0.0020000001]}),
                                       ["loading.inertial_numbers", "p100000_I0.002_s1"]),
    "duplicated_key": (CI_TEXT.replace("  friction: 0.45\n", "  friction: 0.45\n  friction: 0.2\n"),
                       ["duplicate key 'friction'", "first given on line 14", ".yaml:15"]),
    "calibration_set_unknown_pressure": (edited(calibration={"sets": {"high": {"pressures": [2e5]}}}),
                                         ["calibration.sets.high.pressures[0]", "100000"]),
    "calibration_set_unknown_inertial_number": (
        edited(calibration={"sets": {"slow": {"inertial_numbers": [1e-3]}}}),
        ["calibration.sets.slow.inertial_numbers[0]", "0.01"]),
    "calibration_set_unknown_seed": (edited(calibration={"sets": {"odd": {"seeds": [1, 5]}}}),
                                     ["calibration.sets.odd.seeds[1]", "1, 2, 3"]),
    "calibration_set_unknown_protocol": (
        replaced(protocols={"heaviside": {"strain": 0.4}}, calibration={"sets": {"s": {"protocols": ["sinusoidal"]}}}),
        ["calibration.sets.s.protocols[0]", "heaviside"]),
    "calibration_set_bad_name": (edited(calibration={"sets": {"a b": {"protocols": ["heaviside"]}}}),
                                 ["calibration.sets.a b", "letters, digits"]),
    "unknown_sensitivity_set": (edited(compare={"sensitivity_set": "nope"}),
                                ["compare.sensitivity_set", "all, heaviside_only"]),
    "transition_longer_than_protocol": (
        edited(protocols={"heaviside": {"strain": 0.4}, "sinusoidal": {"strain": 0.4, "transition_strain": 0.5}}),
        ["protocols.sinusoidal.transition_strain", "<= 0.4"]),
    "heaviside_shorter_than_a_sample": (edited(protocols={"heaviside": {"strain": 0.001}}),
                                        ["protocols.heaviside.strain", ">= 0.002"]),
    "too_few_samples_for_calibrate": (edited(protocols={"heaviside": {"strain": 0.05}}),
                                      ["protocols.heaviside.strain", "about 26 samples", "needs 50"]),
    "preshear_shorter_than_a_sample": (edited(preshear={"strain": 0.001}), ["preshear.strain", ">= 0.005"]),
    "results_dir_root": (edited(results_dir="/"), ["results_dir", "root of the file system"]),
    "results_dir_empty": (edited(results_dir=""), ["results_dir"]),
    "results_dir_repository": (edited(results_dir="."), ["results_dir", "repository"]),
    "results_dir_code_folder": (edited(results_dir="compare"), ["results_dir", "compare/"]),
    "results_dir_with_space": (edited(results_dir="my results"), ["results_dir", "letters, digits and . _ - /"]),
    # where results_dir and release may lie (preflight/paths.py; issue 33, item 1)
    "results_dir_with_a_backtick": (edited(results_dir="r`touch$IFS./PWNED`"),
                                    ["results_dir", "does not match", "no space, quote, $, backtick"]),
    "results_dir_system_folder": (edited(results_dir="/etc"), ["results_dir", "system folder /etc"]),
    "results_dir_system_folder_even_when_allowed": (edited(results_dir="/usr/local/results", allow_outside_tree=True),
                                                    ["results_dir", "system folder /usr"]),
    "results_dir_outside_the_tree": (edited(results_dir="/var/tmp/someone/results"),
                                     ["results_dir", "outside the working tree", "allow_outside_tree: true"]),
    "results_dir_climbing_out_of_the_tree": (edited(results_dir="results/../../elsewhere"),
                                             ["results_dir", "outside the working tree"]),
    "results_dir_directly_under_the_root": (edited(results_dir="/tmp", allow_outside_tree=True),
                                            ["results_dir", "directly under /"]),
    "results_dir_hidden_folder": (edited(results_dir=".snakemake/results"),
                                  ["results_dir", "hidden folder (.snakemake"]),
    "results_dir_home_folder": (edited(results_dir=str(Path.home()), allow_outside_tree=True),
                                ["results_dir", "home folder"]),
    "opt_in_given_as_text": (edited(results_dir="/var/tmp/x/results", allow_outside_tree="true"),
                             ["allow_outside_tree", "write True"]),
    "release_with_a_backtick": (edited(release="data/x`touch$IFS./PWNED`"), ["release", "does not match"]),
    "release_outside_the_tree": (edited(release="/var/tmp/someone/data/x"),
                                 ["release", "outside the working tree", "allow_outside_tree: true"]),
    "release_in_a_system_folder": (edited(release=["data/bulk-decide", "/usr/share/x"], allow_outside_tree=True),
                                   ["release[1]", "system folder /usr"]),
    "monodisperse_cell": (edited(material={"size_ratio_min": 1.0, "size_ratio_max": 1.0}),
                          ["material.size_ratio_min", "size_ratio_max = 1", "crystal",
                           "size_ratio_min < size_ratio_max"]),
    "cell_too_narrow": (edited(cell={"H_over_d": 4, "W_over_H": 1}, sampling={"bulk_exclusion_d": 1}),
                        ["cell.W_over_H", "3 of the largest disks"]),
    "number_read_as_text": (CI_TEXT.replace("pressures: [1.0e+5]", "pressures: [1.0e5]"),
                            ["loading.pressures[0]", "1.0e+5"]),
    "both_rates": (edited(loading={"pressures": [1e5], "inertial_numbers": [1e-2], "wall_velocities": [0.1]}),
                   ["loading", "not both"]),
    "calibration_option_misspelt": (edited(calibration={"options": "--bootstrapp 8"}),
                                    ["calibration.options", "--bootstrapp is not an option of the program"]),
    "calibration_option_bad_value": (edited(calibration={"options": "--bootstrap eight"}),
                                     ["calibration.options", "--bootstrap: invalid int value: 'eight'"]),
    "compare_option_misspelt": (edited(compare={"options": "--zoom-in 0.05"}),
                                ["compare.options", "--zoom-in is not an option of the program",
                                 "options of python -m compare predict --help"]),
    # options the rule passes itself: a second one would silently replace the rule's (issue 33, item 3)
    "calibration_option_protocols_of_the_workflow": (
        edited(calibration={"options": "--bootstrap 8 --protocols heaviside"}),
        ["calibration.options", "--protocols is the workflow's own", "calibration.sets", "except --dem"]),
    "calibration_option_out_of_the_workflow": (edited(calibration={"options": "--out elsewhere"}),
                                               ["calibration.options", "--out is the workflow's own", "results_dir"]),
    "calibration_option_dem_of_the_workflow": (edited(calibration={"options": "--dem=elsewhere"}),
                                               ["calibration.options", "--dem is the workflow's own"]),
    "calibration_option_freeform_of_its_key": (edited(calibration={"options": "--freeform"}),
                                               ["calibration.options", "--freeform", "calibration.freeform"]),
    "calibration_option_abbreviated": (edited(calibration={"options": "--prot heaviside"}),
                                       ["calibration.options", "--prot is not written in full", "--protocols"]),
    "compare_option_protocols_of_the_workflow": (edited(compare={"options": "--protocols heaviside"}),
                                                 ["compare.options", "--protocols is the workflow's own"]),
    "compare_option_train_protocols_of_the_workflow": (
        edited(compare={"options": "--train-protocols heaviside"}),
        ["compare.options", "--train-protocols is the workflow's own", "calibration.sets"]),
    "calibration_option_with_a_shell_character": (edited(calibration={"options": "--route2-method 'LSODA'"}),
                                                  ["calibration.options", "does not match", "no quote, $"]),
    "schema_range": (edited(cell={"H_over_d": 1}), ["cell.H_over_d", "minimum of 4"]),
    "study_subset_outside_grid": (
        edited(accuracy={"dem_study": True, "base": {"kappa": 1e3, "inertial_number": 1e-2, "H_over_d": 8,
                                                      "dt_over_tc": 0.1, "fine_interval": 0.002,
                                                      "coarse_interval": 0.01},
                         "dem_grid": {"kappa": [1e3, 1e4]}, "default_subset": {"kappa": [3e3]}, "seeds": [1]}),
        ["accuracy.default_subset.kappa", "3000"]),
}


def config_text(edit):
    if isinstance(edit, str):
        return edit
    config = copy.deepcopy(CI)
    edit(config)
    return yaml.safe_dump(config)


#: Cases also run through the real Snakemake dry run: one of each kind of check, so that the
#: Snakefile's wiring (exit 2 before the DAG, no traceback, the file:line) stays tested end to end.
END_TO_END = ["schema_range", "bulk_exclusion_fills_the_gap", "duplicated_key", "calibration_option_misspelt",
              "results_dir_code_folder", "results_dir_system_folder", "monodisperse_cell"]


def write_case(folder, name):
    path = folder / f"{name}.yaml"
    path.write_text(config_text(CASES[name][0]))
    return path


def assert_names_the_key(name, path, message):
    for words in CASES[name][1]:
        assert words.replace(".yaml:", f"{path.name}:") in message, (words, message[-2000:])


@pytest.mark.parametrize("name", list(CASES))
def test_bad_config_is_refused_by_the_preflight_naming_the_key(tmp_path, name):
    path = write_case(tmp_path, name)
    result = preflight_check(path)
    assert result.returncode == 2, result.stderr[-2000:]
    assert result.stderr.strip() and "Traceback" not in result.stderr, result.stderr[-2000:]
    assert_names_the_key(name, path, result.stderr)


def dry_run(path):
    """The dry run of config ``path`` in a working copy of its own (next to the file)."""
    return snakemake("-n", "--configfile", path, cwd=workflow_copy(path.parent / f"{path.stem}-workflow"))


@pytest.fixture(scope="module")
def dry_runs(tmp_path_factory):
    """The END_TO_END cases' dry runs, two at a time: name -> (config path, CompletedProcess)."""
    tmp = tmp_path_factory.mktemp("preflight")
    paths = {name: write_case(tmp, name) for name in END_TO_END}
    with ThreadPoolExecutor(max_workers=2) as pool:
        results = dict(zip(paths, pool.map(dry_run, paths.values())))
    return {name: (paths[name], results[name]) for name in paths}


@pytest.mark.parametrize("name", END_TO_END)
def test_bad_config_stops_snakemake_before_any_job_with_the_preflights_lines(dry_runs, name):
    path, result = dry_runs[name]
    message = result.stdout + result.stderr
    assert result.returncode == 2, message[-2000:]
    assert "Traceback" not in message and "Building DAG" not in message, message[-2000:]
    assert_names_the_key(name, path, message)
    lines = preflight_check(path).stderr
    assert lines.strip() and all(line in message for line in lines.splitlines()), (lines, message[-2000:])


@pytest.mark.parametrize("preset", ["config", "quick", "ci"])
def test_presets_pass_the_preflight(preset):
    path = ROOT / "config" / f"{preset}.yaml"
    assert preflight.check(yaml.safe_load(path.read_text()), [path]) == []


def test_inertial_run_passes_with_the_override():
    config = copy.deepcopy(CI)
    config["loading"] = {"pressures": [1e5], "inertial_numbers": [0.05]}
    assert any("allow_inertial" in line for line in preflight.check(config))
    config["loading"]["allow_inertial"] = True
    assert preflight.check(config) == []


def test_short_runs_pass_when_calibrate_is_told_to_take_fewer_samples():
    config = copy.deepcopy(CI)
    config["protocols"]["heaviside"]["strain"] = 0.05
    assert any("protocols.heaviside.strain" in line for line in preflight.check(config))
    config["calibration"]["options"] = "--min-samples 20"
    assert preflight.check(config) == []


def test_wall_velocity_converts_with_the_nominal_gap():
    # I = 2U/H d / sqrt(p/rho) with H = 10 d: U = 0.1 m/s at p = 1e5 Pa, rho = 2500 -> I = 0.00316
    config = copy.deepcopy(CI)
    config["loading"] = {"pressures": [1e5], "wall_velocities": [0.1]}
    assert preflight.check(config) == []
    from campaign.cases import cases
    assert [c["inertial_number"] for c in cases(config).values()] == pytest.approx([0.02 / 6.3245553] * 3)


def test_every_problem_is_listed_not_only_the_first():
    config = copy.deepcopy(CI)
    config["sampling"].update(fine_interval=0.01, coarse_interval=0.005)
    config["pack"].update(initial_solid_fraction=0.7, solid_fraction_guess=0.6)
    config["compare"] = {"sensitivity_set": "nope"}
    keys = [line.split(" = ")[0] for line in preflight.check(config)]
    assert keys == ["config error: sampling.fine_interval", "config error: pack.initial_solid_fraction",
                    "config error: compare.sensitivity_set"]


@pytest.mark.parametrize("text, words", [
    (None, ["no such file"]),
    ("campaign: x\nloading: {pressures: [1\n", ["bad.yaml:3", "expected ',' or ']'"]),
    ("campaign: x\ncampaign: y\n", ["bad.yaml:2", "duplicate key 'campaign'"]),
    ("- just\n- a list\n", ["must be a mapping"]),
])
def test_config_file_that_cannot_be_read_is_named_with_its_line(tmp_path, text, words):
    path = tmp_path / "bad.yaml"
    if text is not None:
        path.write_text(text)
    result = preflight_check(path)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in result.stderr, result.stderr
    assert all(w in lines[0] for w in words), lines[0]


def test_the_preflight_command_exits_2_with_one_line_naming_a_file_it_cannot_read(tmp_path):
    result = subprocess.run([sys.executable, "-m", "preflight", "check", str(tmp_path / "absent.yaml")],
                            cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert result.returncode == 2 and "Traceback" not in result.stderr, result.stderr
    assert result.stderr.strip() == f"config error: {tmp_path / 'absent.yaml'}: no such file"


def test_results_dir_on_a_scratch_disk_passes_with_allow_outside_tree():
    config = copy.deepcopy(CI)
    config["results_dir"] = "/work/stiff/k1e05"
    assert [line.split(":")[1] for line in preflight.check(config)] == [" results_dir = '/work/stiff/k1e05'"]
    config["allow_outside_tree"] = True
    assert preflight.check(config) == []


def test_a_relative_release_in_the_repository_passes_without_the_opt_in():
    config = copy.deepcopy(CI)
    config["release"] = ["data/bulk-decide", str(ROOT / "data" / "bulk-validation-paper")]
    assert preflight.check(config) == []


def copy_with_preset(folder, preset, text):
    """A working copy whose config/ is its own, with ``preset`` holding ``text`` (None: no such file)."""
    shutil.copytree(ROOT / "config", folder / "config")
    if text is None:
        (folder / "config" / preset).unlink()
    else:
        (folder / "config" / preset).write_text(text)
    return workflow_copy(folder)


@pytest.mark.parametrize("target, preset", [("quick", "quick.yaml"), ("paper", "config.yaml")])
@pytest.mark.parametrize("text, words", [(None, ": no such file"),
                                         ("campaign: x\nloading: {pressures: [1\n", ":3: expected ',' or ']'")])
def test_make_names_a_missing_or_malformed_preset_with_its_line_before_snakemake(tmp_path, target, preset, text,
                                                                                 words):
    folder = copy_with_preset(tmp_path / "copy", preset, text)
    result = subprocess.run(["make", "-o", "setup", target], cwd=folder, capture_output=True, text=True, timeout=300)
    assert result.returncode == 2, result.stdout + result.stderr
    assert f"config error: config/{preset}{words}" in result.stderr, result.stderr
    assert "snakemake" not in result.stdout and "Traceback" not in result.stderr, result.stdout + result.stderr


def test_make_test_checks_the_ci_preset_before_the_suite():
    # under another make (.ci/run's `make test`) a sub-make would print "Entering directory" first
    # (the set-up, YADE's and LAMMPS's installs and the venv, is left out: -o)
    plan = subprocess.run(["make", "--no-print-directory", "-n", "-o", "setup", "-o", "lammps", "test"], cwd=ROOT,
                          capture_output=True, text=True, timeout=60)
    assert plan.stdout.splitlines()[0] == ".venv/bin/python -m preflight check config/ci.yaml", plan.stdout


def test_config_folder_is_named():
    with pytest.raises(preflight.ConfigProblem, match="is a folder"):
        preflight.load_configfile(ROOT / "config")


def test_sets_on_complementary_seeds_take_only_their_seeds():
    from campaign.calibration_sets import calibration_sets
    from campaign.cases import cases

    config = copy.deepcopy(CI)
    config["calibration"]["sets"] = {"odd": {"seeds": [1, 3]}, "even": {"seeds": [2]}}
    table = cases(config)
    built = calibration_sets(config, table)
    seeds = {name: sorted(table[label]["seed"] for label in built[name]["cases"]) for name in ("odd", "even")}
    assert seeds == {"odd": [1, 3], "even": [2]}
    assert not set(built["odd"]["cases"]) & set(built["even"]["cases"])
