"""A campaign's price before it runs (campaign.price): the pre-flight check's line, ``python -m campaign estimate``.

Issue 37's example is the quick preset with wall speeds that give I = 1.2e-4 and 6.0e-5 and two
seeds: hours of DEM where the quick preset takes minutes. It must be priced above the threshold,
naming the inertial number; the quick preset below it; a campaign restored from its release at
no DEM cost.
"""
import json
import shutil

import pytest
import yaml

from campaign import cost, price
from campaign.schema_defaults import with_defaults
from tests.helpers import ROOT, preflight_check, run_main

QUICK = yaml.safe_load((ROOT / "config" / "quick.yaml").read_text())
DECIDE = yaml.safe_load((ROOT / "config" / "bulk_decide.yaml").read_text())


def write(tmp_path, config, name="campaign.yaml"):
    config = {**config, "results_dir": str(tmp_path / "results"), "allow_outside_tree": True}
    path = tmp_path / name
    path.write_text(yaml.safe_dump(config, sort_keys=False))
    return path


def issue_example(tmp_path):
    loading = {"pressures": [5.0e4, 2.0e5], "wall_velocities": [0.01]}
    return write(tmp_path, {**QUICK, "loading": loading, "seeds": [1, 2]})


def test_the_issues_example_is_priced_above_an_hour_naming_the_inertial_number(tmp_path):
    r = preflight_check(issue_example(tmp_path))
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0].endswith(": ok")
    assert lines[1].startswith("price: campaign quick: 4 DEM cases, 4 core-hours, about 2.0 h on 2 cores")
    assert "on a cluster with one core per job (YADE's throughput: documented)" in lines[1]
    assert lines[2] == ("price: campaign quick takes more than 1 h on 2 cores; what drives the cost: the inertial "
                        "number 6.04e-5, 83 times slower than the quick preset's 0.005 (each stage: python -m "
                        "campaign estimate --configfile ...)")


def test_the_quick_preset_is_priced_below_the_threshold(tmp_path):
    r = preflight_check(write(tmp_path, QUICK), "--cores", "2")
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert len(lines) == 2 and lines[1].startswith("price: campaign quick: 6 DEM cases, 0.19 core-hours, about ")
    assert "takes more than" not in r.stdout


def test_on_one_core_the_wall_time_is_the_core_time_and_on_many_the_longest_chain(tmp_path):
    config = yaml.safe_load(issue_example(tmp_path).read_text())
    one, many = price.price(config, cores=1), price.price(config, cores=64)
    assert one.wall_s == pytest.approx(one.core_s)
    assert many.wall_s == pytest.approx(many.cluster_s) and many.cluster_s < one.core_s / 3


def test_the_largest_ratio_to_the_quick_preset_names_the_driver():
    paper = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    drivers = price.cost_drivers(price.campaign_scenes(paper), price.campaign_scenes(QUICK))
    ratio, text = drivers[0]
    assert text.startswith("the cell of 5010 disks") and ratio > 10
    assert [r for r, _ in drivers] == sorted((r for r, _ in drivers), reverse=True)
    stiff = {**QUICK, "material": {**QUICK["material"], "kappa": 1.0e5}, "loading": {**QUICK["loading"],
                                                                                     "inertial_numbers": [5.0e-3]}}
    ratio, text = price.cost_drivers(price.campaign_scenes(stiff), price.campaign_scenes(QUICK))[0]
    assert text.startswith("kappa 1e5, 10 times slower") and ratio == pytest.approx(10)


def test_a_dem_study_the_config_runs_is_priced_on_a_line_of_its_own(tmp_path):
    paper = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    r = preflight_check(write(tmp_path, paper))
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[1].startswith("price: campaign paper: 4 DEM cases, 9.3 core-hours")
    assert "the cell of 5010 disks, 21 times slower per step than the quick preset's 626" in lines[2]
    assert lines[3].startswith("price: and the DEM resolution study (accuracy.dem_study): 19 DEM cases, 1.4 "
                               "core-hours, about ")


def test_a_campaign_restored_from_its_release_costs_no_dem(tmp_path):
    r = preflight_check(write(tmp_path, DECIDE))
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines()[1] == ("price: campaign bulk_decide: all 5 DEM cases restored from the release "
                                        "data/bulk-decide: no DEM to run, no DEM cost")


def test_a_new_seed_beside_a_release_is_the_only_case_priced(tmp_path):
    r = preflight_check(write(tmp_path, {**DECIDE, "seeds": [*DECIDE["seeds"], 7]}))
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines()[1].startswith("price: campaign bulk_decide: 1 DEM case (5 more restored from "
                                               "data/bulk-decide, at no cost), 0.46 core-hours")


def test_estimate_prints_every_stage_and_the_documented_throughput_without_earlier_runs(tmp_path):
    r = run_main("campaign.__main__", ["estimate", "--configfile", issue_example(tmp_path), "--cores", "2"])
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0].split() == ["case", "stage", "N", "steps", "core_s", "throughput"]
    rows = [line.split() for line in lines[1:17]]
    assert [row[1] for row in rows[:4]] == ["pack", "preshear", "heaviside", "sinusoidal"]
    assert {row[0] for row in rows} == {"p50000_I0.000120869_s1", "p50000_I0.000120869_s2",
                                        "p200000_I6.04343e-05_s1", "p200000_I6.04343e-05_s2"}
    assert all(row[2] == "626" and row[5] == "documented" for row in rows)
    assert lines[17].startswith("throughput: the documented figure")
    assert lines[18].startswith("total: 4.02 core-hours; about 2.0 h on 2 cores")
    assert "the inertial number 6.04e-5, 83 times slower" in lines[19]


def test_estimate_prices_at_the_throughput_of_the_campaigns_earlier_runs(tmp_path):
    unreleased = {key: value for key, value in DECIDE.items() if key != "release"}
    path = write(tmp_path, {**unreleased, "seeds": [1, 3, 9]})
    for seed in (1, 3):
        case = f"p100000_I0.001_s{seed}"
        shutil.copytree(ROOT / "data" / "bulk-decide" / "cases" / case / "sidecars", tmp_path / "results" / "dem" / case)
    r = run_main("campaign.__main__", ["estimate", "--configfile", path])
    assert r.returncode == 0, r.stderr
    assert "throughput: measured on this machine: 8 stage sidecars of 2 cases in" in r.stdout
    assert " measured\n" in r.stdout and "documented\n" not in r.stdout
    measured = sum(json.loads(p.read_text())["cpu_time_s"] for p in (tmp_path / "results" / "dem").glob("*/*.json")
                   if "cpu_time_s" in json.loads(p.read_text()))
    p = price.price(with_defaults(yaml.safe_load(path.read_text())))
    # three seeds priced at the rate two of them ran at: 3/2 of their CPU, to the pack's projection
    assert p.core_s == pytest.approx(1.5 * measured, rel=0.03)


def test_a_lammps_campaign_is_priced_at_lammps_documented_throughput_not_at_yades_earlier_runs(tmp_path):
    unreleased = {key: value for key, value in DECIDE.items() if key != "release"}
    config = with_defaults({**unreleased, "seeds": [1, 3, 9], "results_dir": str(tmp_path / "results")})
    for seed in (1, 3):   # YADE's sidecars (no engine key)
        case = f"p100000_I0.001_s{seed}"
        shutil.copytree(ROOT / "data" / "bulk-decide" / "cases" / case / "sidecars",
                        tmp_path / "results" / "dem" / case)
    yade, lammps = price.price(config), price.price({**config, "engine": "lammps"})
    assert yade.throughput.measured and lammps.throughput is cost.documented("lammps")
    yade_documented = price.stage_table(price.campaign_scenes(config))["core_s"].sum()
    assert lammps.core_s == pytest.approx(yade_documented / cost.LAMMPS_OVER_YADE)
    assert set(lammps.table["throughput"]) == {"documented"}
    assert lammps.throughput.source.startswith("the documented figure (LAMMPS")
    assert "per job (LAMMPS's throughput: documented)" in price.price_lines(lammps)[0]


def test_snakemake_prints_the_price_before_any_job(shared_dry_run):
    result = shared_dry_run("--configfile", "config/quick.yaml")
    assert result.returncode == 0, result.stderr
    line = next(line for line in result.stderr.splitlines() if line.startswith("price:"))
    assert line.startswith("price: campaign quick: 6 DEM cases, 0.19 core-hours, about ")
