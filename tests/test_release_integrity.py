"""A data release is used only as released (docs/data-release.md, "Where a release is checked").

Each test copies one case of the committed release ``data/bulk-decide`` into a
one-case release under ``tmp_path`` (its files and the manifest's entries for
them, unchanged), shows that the untouched copy is accepted, then edits it as
issue 33 did (one A_xy value of a series, one byte of a sidecar's ``dt``) and
checks that ``python -m dem_contract restore`` and the workflow's release rules
refuse it before writing anything, naming the file.
"""
import gzip
import shutil
from pathlib import Path

import pytest
import yaml

from dem_contract import release
from tests.helpers import dry_run, run_main

ROOT = Path(__file__).resolve().parents[1]
DECIDE = ROOT / "data" / "bulk-decide"
LABEL = "p100000_I0.001_s1"

pytestmark = pytest.mark.skipif(not DECIDE.is_dir(), reason="the deciding campaign's release is not in data/")


def one_case_release(folder: Path, label: str = LABEL) -> Path:
    """A release of ``label`` alone, copied from ``data/bulk-decide``: its files and manifest entries as released."""
    manifest = release.read_manifest(DECIDE)
    keep = {name: entry for name, entry in manifest["files"].items()
            if name == "config.yaml" or name.startswith(f"{release.CASES_DIR}/{label}/")}
    for name in keep:
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(DECIDE / name, folder / name)
    manifest.update(cases={label: manifest["cases"][label]}, files=keep,
                    total_bytes=sum(e["bytes"] for e in keep.values()))
    manifest.pop("published", None)
    (folder / release.MANIFEST).write_text(yaml.safe_dump(manifest, sort_keys=False))
    return folder


def edit_one_A_xy_value(folder: Path) -> Path:
    """One A_xy value of one row of the case's train03 series moved by 0.01 (the file stays valid gzip CSV)."""
    path = folder / release.CASES_DIR / LABEL / "train03.csv.gz"
    lines = gzip.open(path, "rt").read().split("\n")
    column = lines[0].split(",").index("A_xy")
    row = lines[200].split(",")
    row[column] = repr(float(row[column]) + 0.01)
    lines[200] = ",".join(row)
    path.write_bytes(gzip.compress("\n".join(lines).encode(), mtime=0))
    return path


def edit_one_byte_of_dt(folder: Path) -> Path:
    """One digit of the train03 sidecar's ``dt`` changed: one byte, same size."""
    path = folder / release.CASES_DIR / LABEL / "sidecars" / "train03.json"
    text = path.read_text()
    at = text.index('"dt": ') + len('"dt": ') + 3          # the third character of the value: a digit
    text = text[:at] + ("1" if text[at] != "1" else "2") + text[at + 1:]
    path.write_text(text)
    return path


def restore(folder: Path, out: Path):
    return run_main("dem_contract.__main__", ["restore", "--release", folder, "--case", LABEL, "--out", out])


@pytest.mark.parametrize("edit", [edit_one_A_xy_value, edit_one_byte_of_dt], ids=["series value", "sidecar byte"])
def test_restore_refuses_a_release_whose_file_was_edited_naming_the_file(tmp_path, edit):
    """The untouched copy restores; after one edit, restore exits 2 naming the file, and writes nothing."""
    folder = one_case_release(tmp_path / "release")
    done = restore(folder, tmp_path / "untouched" / LABEL)
    assert done.returncode == 0, done.stderr
    assert {p.name for p in (tmp_path / "untouched" / LABEL).glob("*.csv")} == {
        "preshear.csv", "sinusoidal.csv", "train03.csv", "train05.csv"}
    edited = edit(folder)
    done = restore(folder, tmp_path / "edited" / LABEL)
    assert done.returncode == 2
    assert f"{edited}: sha256 " in done.stderr and "edited after the release" in done.stderr
    assert not (tmp_path / "edited").exists()


def test_the_workflow_refuses_an_edited_release_while_it_is_parsed_naming_the_file(tmp_path, workflow_dir):
    """A preset whose ``release:`` names an edited release stops before any job (exit 2), naming the file;
    the untouched copy is planned as released (its case restored, not run)."""
    folder = one_case_release(tmp_path / "release")
    args = ["--configfile", "config/bulk_decide.yaml", "--config", f"results_dir={tmp_path / 'results'}",
            f"release={folder}", "allow_outside_tree=True"]   # pytest's tmp_path
    plan = dry_run(*args, cwd=workflow_dir)
    assert plan.returncode == 0 and "release_case" in plan.stdout, plan.stderr[-3000:]
    edited = edit_one_A_xy_value(folder)
    plan = dry_run(*args, cwd=workflow_dir)
    assert plan.returncode == 2
    assert f"config key 'release': {folder}: 1 file(s) differ from the manifest" in plan.stderr
    assert f"{edited}: sha256 " in plan.stderr
