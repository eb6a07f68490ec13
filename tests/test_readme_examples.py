"""The READMEs' examples run as written, so the READMEs cannot drift from the code.

Every fenced ``python`` block of README.md and model/README.md that imports ``model``
runs as a script, and every line of a fenced ``bash`` block that calls
``python -m model`` runs in a shell, each in a fresh temporary directory (``python``
on PATH is this interpreter, the repository on PYTHONPATH). The input files the
examples name (a calibration's ``params.yaml``, ``P.yaml``, ``dem_run.csv``) are
written there first; an example that names a new input fails until it is added to
``INPUTS``.

Every other command line of README.md's fenced ``bash`` blocks (``make``, Snakemake,
``python -m preflight``...) runs in a private working copy of the workflow and must exit 0:
as written when it takes under a minute, as a dry run when it would run a campaign
(``make -n <target>``; ``snakemake -n ...``; a ``--report`` needs a finished run, so its
command is dry-run without it).
"""
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

from model import default_params, load_params, save_params

ROOT = Path(__file__).resolve().parents[1]
READMES = ("README.md", "model/README.md")
FENCE = re.compile(r"^```(\w*)\n(.*?)^```", re.M | re.S)
IMPORTS_MODEL = re.compile(r"^\s*(from|import)\s+model\b", re.M)
CALLS_MODEL = re.compile(r"^\s*python -m model\b")


def _write_params(path):
    path.parent.mkdir(parents=True, exist_ok=True)
    save_params(default_params(), path)


def _write_reversal_table(path):
    """A DEM-like imposed history: shear at 1, a linear ramp through zero, shear at -1."""
    pd.DataFrame({"t": [0.0, 1.0, 1.2, 3.0], "gammadot": [1.0, 1.0, -1.0, -1.0]}).to_csv(path, index=False)


INPUTS = {
    "results/calibration/all/params.yaml": _write_params,
    "P.yaml": _write_params,
    "dem_run.csv": _write_reversal_table,
}


def readme_examples():
    """(id, kind, code) for every model example of the READMEs, in order."""
    found = []
    for readme in READMES:
        text = (ROOT / readme).read_text()
        for block in FENCE.finditer(text):
            lang, body = block.group(1), block.group(2)
            first = text.count("\n", 0, block.start()) + 2      # line number of the block's first line
            if lang == "python" and IMPORTS_MODEL.search(body):
                found.append((f"{readme}:{first}", "python", body))
            elif lang == "bash":
                for k, line in enumerate(body.splitlines()):
                    if CALLS_MODEL.match(line):
                        found.append((f"{readme}:{first + k}", "bash", line))
    return found


EXAMPLES = readme_examples()


@pytest.fixture
def workdir(tmp_path):
    for name, write in INPUTS.items():
        write(tmp_path / name)
    bindir = tmp_path / ".bin"
    bindir.mkdir()
    shim = bindir / "python"                       # a symlink would lose the virtual environment
    shim.write_text(f'#!/bin/sh\nexec "{sys.executable}" "$@"\n')
    shim.chmod(0o755)
    env = dict(os.environ, PATH=f"{bindir}{os.pathsep}{os.environ['PATH']}", PYTHONPATH=str(ROOT), MPLBACKEND="Agg")
    return tmp_path, env


def test_the_readmes_show_the_model_api_and_its_command_line():
    """Guards the extraction itself: without this, a renamed fence would make every example vanish silently."""
    kinds = [kind for _, kind, _ in EXAMPLES]
    assert kinds.count("python") >= 1 and kinds.count("bash") >= 4, EXAMPLES
    commands = " ".join(code for _, kind, code in EXAMPLES if kind == "bash")
    for word in ("simulate", "--protocol sinusoidal", "--protocol table", "defaults"):
        assert word in commands


@pytest.mark.parametrize("where, kind, code", EXAMPLES, ids=[e[0] for e in EXAMPLES])
def test_readme_example_runs_as_written(where, kind, code, workdir):
    cwd, env = workdir
    if kind == "python":
        (cwd / "example.py").write_text(code)
        cmd = [sys.executable, "example.py"]
    else:
        cmd = ["bash", "-e", "-c", code]
    run = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, f"{where} failed:\n{code}\n{run.stdout}\n{run.stderr}"
    assert "Traceback" not in run.stderr, run.stderr
    wrote = re.search(r"wrote (\S+) and (\S+)", run.stdout)
    if "python -m model simulate" in code:
        assert wrote, run.stdout
    for path in wrote.groups() if wrote else ():
        assert (cwd / path).stat().st_size > 0, path
    promised = re.search(r"->\s*(\S+)\.\{(\w+),(\w+)\}", code)      # "-> results/model/heaviside.{csv,png}"
    if promised:
        stem, *suffixes = promised.groups()
        for suffix in suffixes:
            assert (cwd / f"{stem}.{suffix}").stat().st_size > 0, f"{where} promises {stem}.{suffix}"
    if re.search(r"python -m model defaults\b", code):
        (cwd / "printed.yaml").write_text(run.stdout)
        assert load_params(cwd / "printed.yaml") == default_params()


# --- README.md's shell commands ----------------------------------------------------------------

def readme_commands(readme="README.md"):
    """(id, command) for every command line of README.md's fenced bash blocks but the model's examples."""
    text = (ROOT / readme).read_text()
    found = []
    for block in FENCE.finditer(text):
        if block.group(1) != "bash":
            continue
        first = text.count("\n", 0, block.start()) + 2
        for k, line in enumerate(block.group(2).splitlines()):
            if line.strip() and not line.lstrip().startswith("#") and not CALLS_MODEL.match(line):
                found.append((f"{readme}:{first + k}", line))
    return found


COMMANDS = readme_commands()


def as_run(line):
    """The argument list that checks README command ``line``: a dry run for what runs a campaign."""
    words = shlex.split(line, comments=True)
    if words[0] == "make":                           # every target installs or runs a campaign
        return ["make", "-n", *words[1:]]
    if words[0].endswith("snakemake") and "--unlock" not in words:
        if "--report" in words:                      # needs a finished run: check the rest of the line
            at = words.index("--report")
            del words[at:at + 2]
        return [words[0], "-n", *words[1:]]
    return words


def test_the_readme_shows_the_set_up_the_presets_and_the_cluster():
    """Guards the extraction: the commands a new user copies are all fenced, so all of them are run."""
    lines = [line for _, line in COMMANDS]
    for expected in ("make quick", "make test", "--configfile config/quick.yaml", "--profile profiles/slurm",
                     "python -m preflight check", "--report", "results/claims/README_section.md"):
        assert any(expected in line for line in lines), expected


@pytest.mark.parametrize("where, line", COMMANDS, ids=[c[0] for c in COMMANDS])
def test_readme_command_exits_0(where, line, workflow_dir):
    run = subprocess.run(as_run(line), cwd=workflow_dir, capture_output=True, text=True, timeout=300,
                         env=dict(os.environ, MPLBACKEND="Agg"))
    assert run.returncode == 0, f"{where}: {line}\n{run.stdout[-2000:]}\n{run.stderr[-3000:]}"
