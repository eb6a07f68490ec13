"""A data release's engine, compression, run commit and remake (docs/data-release.md, "Commands").

- A LAMMPS case (a real tiny one: pack, pre-shear and Heaviside reversal, about 20 s of LAMMPS) is
  released naming LAMMPS and its version (``case.yaml``'s simulator, the manifest's ``engine`` and
  ``lammps_version``), and read back; a YADE case released again from its committed release keeps
  its ``case.yaml``, series and sidecars byte for byte, and the manifest its keys.
- ``--compression xz``: the same series as gzip (restored value for value), deterministic bytes,
  smaller, checked and read like gzip.
- ``--run-commit``: ``dem_code_commit`` is the last change of the DEM's code at or before the commit
  that ran the DEM; a commit that is not HEAD's ancestor is refused before anything is written.
- ``--carry-from``: a release remade without its states keeps the old manifest's blocks the command
  does not write (comments included), its published provenance, and records the remake.
"""
import gzip
import json
import shutil
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
import yaml

from dem_contract import DEMInputError, read_series, release
from tests.helpers import LAMMPS_RUN, make_scene, yade

ROOT = Path(__file__).resolve().parents[1]
PAPER = ROOT / "data" / "bulk-validation-paper"
YADE_LABEL = "narrow-H37-W18_s1"
LAMMPS_LABEL = "p100000_I0.01_s1"
#: A YADE release's manifest keys, in order, as every release before LAMMPS and xz wrote them.
YADE_KEYS = ["release", "license", "date", "code_commit", "code_dirty", "dem_code_commit", "yade_version", "states",
             "regenerate", "cases", "config", "files", "total_bytes"]
CONFIGS = [PAPER / "config-1.yaml", PAPER / "config-2.yaml"]

pytestmark = pytest.mark.skipif(not PAPER.is_dir(), reason="data/bulk-validation-paper is not in data/")


def cli(*args):
    return subprocess.run([sys.executable, "-m", "dem_contract", *map(str, args)], cwd=ROOT, capture_output=True,
                          text=True, timeout=600)


@pytest.fixture(scope="module")
def yade_case(tmp_path_factory):
    """A committed YADE case restored as a finished case of the bulk study: <results>/accuracy/bulk/<label>."""
    results = tmp_path_factory.mktemp("yade") / "results"
    return release.restore_case(PAPER, YADE_LABEL, results / "accuracy" / "bulk" / YADE_LABEL)


@pytest.fixture(scope="module")
def lammps_case(tmp_path_factory):
    """A real tiny LAMMPS case (tests/test_lammps_stages.py's cell): pack, pre-shear, Heaviside, in <results>/dem."""
    case = tmp_path_factory.mktemp("lammps") / "results" / "dem" / LAMMPS_LABEL
    case.mkdir(parents=True)
    scene = dict(make_scene(), engine="lammps")
    (case / "scene.json").write_text(json.dumps(scene))
    for stage in ("pack", "preshear", "heaviside"):
        r = yade(LAMMPS_RUN, case / "scene.json", stage, case)
        assert r.returncode == 0, f"{stage}: {r.stdout[-2000:]}\n{r.stderr[-2000:]}"
    return case


def test_a_yade_case_released_again_keeps_its_files_and_the_manifest_its_keys(yade_case, tmp_path):
    """Restore -> release (gzip, no states): case.yaml, series and sidecars equal the committed release's byte for
    byte, the manifest's keys are a YADE release's, the case's entry is the committed one."""
    out = release.make_release([yade_case], tmp_path / "again", CONFIGS, "test")
    manifest = release.read_manifest(out)
    committed = release.read_manifest(PAPER)
    assert list(manifest) == YADE_KEYS
    assert manifest["yade_version"] == "2023.02a" and manifest["cases"][YADE_LABEL] == committed["cases"][YADE_LABEL]
    ours = {n: f for n, f in manifest["files"].items() if n.startswith("cases/")}
    assert ours and all(committed["files"][n] == f for n, f in ours.items()), "a released file changed"
    case_yaml = (out / "cases" / YADE_LABEL / "case.yaml").read_text()
    assert case_yaml == (PAPER / "cases" / YADE_LABEL / "case.yaml").read_text()
    assert "simulator: YADE 2023.02a\n" in case_yaml


@pytest.mark.lammps
@pytest.mark.slow
def test_a_lammps_case_is_released_naming_lammps_and_read_back(lammps_case, yade_case, tmp_path):
    side = json.loads((lammps_case / "preshear.json").read_text())
    version = side["lammps_version"]
    assert side["engine"] == "lammps" and "yade_version" not in side and version >= 20210929
    out = release.make_release([lammps_case], tmp_path / "lammps", CONFIGS[0], "test", with_states=True)
    meta = yaml.safe_load((out / "cases" / LAMMPS_LABEL / "case.yaml").read_text())
    assert meta["simulator"] == f"LAMMPS {version}"
    manifest = release.read_manifest(out)
    assert (manifest["engine"], manifest["lammps_version"]) == ("lammps", version) and "yade_version" not in manifest
    assert manifest["cases"][LAMMPS_LABEL]["engine"] == "lammps"
    assert manifest["cases"][LAMMPS_LABEL]["lammps_version"] == version
    assert f"cases/{LAMMPS_LABEL}/preshear.final.lammps" in manifest["files"]   # LAMMPS's state, with --states
    assert release.verify(out) == []
    restored = release.restore_case(out, LAMMPS_LABEL, tmp_path / "restored" / LAMMPS_LABEL)
    assert json.loads((restored / "scene.json").read_text())["engine"] == "lammps"
    for stem in ("preshear", "heaviside"):
        pd.testing.assert_frame_equal(pd.read_csv(restored / f"{stem}.csv").astype(float),
                                      pd.read_csv(lammps_case / f"{stem}.csv").astype(float), check_exact=True)
    assert (restored / "preshear.final.lammps").read_bytes() == (lammps_case / "preshear.final.lammps").read_bytes()
    mixed = release.read_manifest(release.make_release([lammps_case, yade_case], tmp_path / "mixed", CONFIGS, "t"))
    assert mixed["engine"] == ["lammps", "yade"]
    assert (mixed["lammps_version"], mixed["yade_version"]) == (version, "2023.02a")
    assert mixed["cases"][YADE_LABEL]["yade_version"] == "2023.02a" and "engine" not in mixed["cases"][YADE_LABEL]


def test_xz_gives_the_same_series_deterministic_and_smaller(yade_case, tmp_path):
    """An xz release restores to the series a gzip release restores to, value for value; equal data give equal
    bytes; its checksums hold and the importer reads it; a truncated xz file is refused by name."""
    gz = release.make_release([yade_case], tmp_path / "gz", CONFIGS, "test")
    xz = release.make_release([yade_case], tmp_path / "xz", CONFIGS, "test", compression="xz")
    again = release.make_release([yade_case], tmp_path / "xz-again", CONFIGS, "test", compression="xz")
    manifest = release.read_manifest(xz)
    assert manifest["compression"] == "xz" and "compression" not in release.read_manifest(gz)
    runs = yaml.safe_load((xz / "cases" / YADE_LABEL / "case.yaml").read_text())["cases"][0]["runs"]
    assert [r["file"] for r in runs] == ["heaviside.csv.xz"]
    assert manifest["files"] == release.read_manifest(again)["files"]        # the same bytes, made twice
    series_gz, series_xz = (p / "cases" / YADE_LABEL / f"heaviside.csv.{c}" for p, c in ((gz, "gz"), (xz, "xz")))
    assert series_xz.stat().st_size < 0.92 * series_gz.stat().st_size
    assert release.verify(xz) == []
    a = release.restore_case(gz, YADE_LABEL, tmp_path / "from-gz" / YADE_LABEL)
    b = release.restore_case(xz, YADE_LABEL, tmp_path / "from-xz" / YADE_LABEL)
    for stem in ("preshear", "heaviside"):
        pd.testing.assert_frame_equal(read_series(b / f"{stem}.csv"), read_series(a / f"{stem}.csv"), check_exact=True)
    frame = pd.read_csv(gzip.open(series_gz))
    release.write_csv_xz(frame, tmp_path / "one.csv.xz")
    release.write_csv_xz(frame, tmp_path / "two.csv.xz")
    assert (tmp_path / "one.csv.xz").read_bytes() == (tmp_path / "two.csv.xz").read_bytes()
    pd.testing.assert_frame_equal(read_series(tmp_path / "one.csv.xz"), read_series(series_gz), check_exact=True)
    data = (tmp_path / "one.csv.xz").read_bytes()
    (tmp_path / "one.csv.xz").write_bytes(data[: len(data) // 2])
    with pytest.raises(DEMInputError, match=r"one.csv.xz: not a readable CSV"):
        read_series(tmp_path / "one.csv.xz")


def git(repo, *args):
    return subprocess.run(["git", "-c", "user.name=t", "-c", "user.email=t@t", *args], cwd=repo, check=True,
                          capture_output=True, text=True).stdout.strip()


def commit(repo, path, text, message):
    (repo / path).parent.mkdir(parents=True, exist_ok=True)
    (repo / path).write_text(text)
    git(repo, "add", path)
    git(repo, "commit", "-q", "-m", message)
    return git(repo, "rev-parse", "HEAD")


def test_run_commit_names_the_dem_code_of_the_commit_that_ran_it(yade_case, lammps_case, tmp_path):
    """History A (YADE's stages) - B (LAMMPS's stages) - C (docs), and D (YADE's stages) on a branch from A:
    released at C with --run-commit A, dem_code_commit is A and run_commit A; without it, a YADE case's is A
    (B changed LAMMPS's code only), a LAMMPS case's B; D is not HEAD's ancestor: refused."""
    repo = tmp_path / "repo"
    repo.mkdir()
    git(repo, "init", "-q", "-b", "main")
    a = commit(repo, "yade_scripts/stages.py", "a\n", "A")
    b = commit(repo, "lammps_scripts/stages.py", "b\n", "B")
    c = commit(repo, "docs/x.md", "c\n", "C")
    git(repo, "checkout", "-q", "-b", "side", a)
    d = commit(repo, "yade_scripts/stages.py", "d\n", "D")
    git(repo, "checkout", "-q", "main")
    pinned = release.read_manifest(release.make_release([yade_case], tmp_path / "pinned", CONFIGS, "t", repo=repo,
                                                        run_commit=a[:7]))
    assert (pinned["code_commit"], pinned["run_commit"], pinned["dem_code_commit"]) == (c, a, a)
    assert list(pinned).index("run_commit") == list(pinned).index("code_dirty") + 1
    plain = release.read_manifest(release.make_release([yade_case], tmp_path / "plain", CONFIGS, "t", repo=repo))
    assert plain["dem_code_commit"] == a and "run_commit" not in plain     # lammps_scripts/ is not YADE's code
    lammps = release.read_manifest(release.make_release([lammps_case], tmp_path / "lammps", CONFIGS, "t", repo=repo))
    assert lammps["dem_code_commit"] == b                                # ... but LAMMPS's
    with pytest.raises(DEMInputError, match=f"--run-commit {d}: not an ancestor of HEAD"):
        release.make_release([yade_case], tmp_path / "side", CONFIGS, "t", repo=repo, run_commit=d)
    assert not (tmp_path / "side").exists()


def test_run_commit_on_this_repository_and_an_unknown_commit(yade_case, tmp_path):
    """The committed release's own code_commit as --run-commit gives its dem_code_commit; a commit that is not
    in the repository exits 2 naming it, writing nothing."""
    committed = release.read_manifest(PAPER)
    run = cli("release", "--cases", yade_case, "--config", *CONFIGS, "--out", tmp_path / "pinned",
              "--run-commit", committed.get("run_commit", committed["code_commit"]))
    assert run.returncode == 0, run.stderr
    assert release.read_manifest(tmp_path / "pinned")["dem_code_commit"] == committed["dem_code_commit"]
    bad = cli("release", "--cases", yade_case, "--config", *CONFIGS, "--out", tmp_path / "bad",
              "--run-commit", "0123456789abcdef0123456789abcdef01234567")
    assert bad.returncode == 2 and "--run-commit 0123456789abcdef0123456789abcdef01234567: not a commit" in bad.stderr
    assert not (tmp_path / "bad").exists()


SEEDS_BLOCK = """seeds:
  # planned, run and excluded (a comment the remake keeps)
  planned: [1, 2]   # 2026-11-26, commit de74855
  released: [1]
  records:
  - {seed: 2, status: excluded, reason: "its pre-shear stopped on the pressure guard"}
"""


def test_a_release_remade_without_states_carries_the_old_manifest_over(yade_case, tmp_path):
    """An old release with a (dummy) state, a published table and blocks added after it was made (seeds, with
    comments; republished), remade from its restored case without --states and --carry-from: the blocks verbatim,
    the published provenance the old one, a remade entry (every kept file's sha256 equal, the state dropped), and
    the CLI prints the comparison."""
    case = tmp_path / "results" / "accuracy" / "bulk" / YADE_LABEL
    shutil.copytree(yade_case, case)
    (case / release.STATE).write_bytes(b"a state\n")
    table = tmp_path / "results" / "accuracy" / "bulk_vs_walls.csv"
    table.write_text("cell,match\nnarrow,True\n")
    old = release.make_release([case], tmp_path / "data" / "x", CONFIGS, "the original command", with_states=True,
                               published=[table])
    provenance = {"bulk_vs_walls.csv": "results-bulk/accuracy/bulk_vs_walls.csv"}    # where the campaign wrote it
    text = yaml.safe_dump(dict(release.read_manifest(old), published=provenance), sort_keys=False)
    text = text.replace("regenerate:\n", SEEDS_BLOCK + "regenerate:\n", 1)
    text += "republished:\n- {date: '2026-11-27T00:00:00Z', reason: tables regenerated}\n"
    (tmp_path / "old.yaml").write_text(text)
    shutil.rmtree(old)
    restored = release.restore_case(release.make_release([case], tmp_path / "tmp-release", CONFIGS, "t",
                                                         with_states=True),
                                    YADE_LABEL, tmp_path / "again" / "accuracy" / "bulk" / YADE_LABEL)
    copy = tmp_path / "again" / "accuracy" / "bulk_vs_walls.csv"
    shutil.copyfile(table, copy)
    run = cli("release", "--cases", restored, "--config", *CONFIGS, "--out", old, "--published", copy,
              "--carry-from", tmp_path / "old.yaml", "--reason", "the 20 MB budget: states dropped")
    assert run.returncode == 0, run.stderr
    assert "file(s) kept with equal sha256, 0 changed, 1 dropped, 0 added" in run.stdout
    assert f"dropped: cases/{YADE_LABEL}/{release.STATE}" in run.stdout
    new_text = (old / release.MANIFEST).read_text()
    assert "states: false\n" + SEEDS_BLOCK + "remade:\n" in new_text
    assert new_text.endswith("republished:\n- {date: '2026-11-27T00:00:00Z', reason: tables regenerated}\n")
    manifest = release.read_manifest(old)
    assert manifest["published"] == provenance
    (remade,) = manifest["remade"]
    assert remade["reason"] == "the 20 MB budget: states dropped" and remade["from"]["command"] == "the original command"
    assert remade["files"]["changed"] == [] and remade["files"]["dropped"] == [f"cases/{YADE_LABEL}/{release.STATE}"]
    assert remade["files"]["kept_with_equal_sha256"] == len(manifest["files"])
    assert remade["commands"][0] == f"python -m dem_contract restore --release {old} --case {YADE_LABEL} --out {restored}"
    assert remade["commands"][-1] == manifest["regenerate"]["release"]
    assert release.verify(old) == []
    shutil.rmtree(old)
    no_reason = cli("release", "--cases", restored, "--config", *CONFIGS, "--out", old,
                    "--carry-from", tmp_path / "old.yaml")
    assert no_reason.returncode == 2 and "give --reason" in no_reason.stderr and not old.exists()
