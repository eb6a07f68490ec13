"""Every command line turns bad input into exit status 2 and one line naming the file (and line or key).

Each row of ``CASES`` runs a command line on one malformed or missing input and checks: exit
status 2, no Python traceback, and a message holding the strings a user needs to find the
problem (the file, and the line of malformed YAML or the key at fault). The first row of each
package runs the real command line as a user would (``python -m ...`` in a subprocess: the
interpreter, the package's imports and ``__main__``); the others call the function that
``__main__`` hands the arguments to, in this process (about 1.3 s of CPU less each: the same
code reads the input and writes the message), with every warning written to the captured
stderr as a process would print it.
"""
import subprocess
import sys
from pathlib import Path

import pytest

from model import default_params, save_params
from tests.helpers import run_main

ROOT = Path(__file__).resolve().parents[1]

#: Malformed YAML whose error yaml places on line 3 ("mapping values are not allowed here").
MALFORMED_YAML = "format: fabric-friction-params\nversion: 1\nmodel1: a1: 1\n"


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """Bad inputs of every kind, and a few good ones to pair them with, in one folder."""
    d = tmp_path_factory.mktemp("cli_inputs")
    (d / "malformed.yaml").write_text(MALFORMED_YAML)
    (d / "a_directory").mkdir()
    (d / "a_file").write_text("not a folder\n")
    good = d / "good.yaml"
    save_params(default_params(), good)
    (d / "version_one.yaml").write_text(good.read_text().replace("version: 2", "version: one"))
    (d / "bad_key.yaml").write_text(good.read_text().replace("X_c:", "Xc:"))
    (d / "cut_table.csv").write_text("t,gammadot\n0,1\n1,1\n2,\n")
    (d / "no_rate.csv").write_text("t,rate\n0,1\n1,1\n")
    (d / "points.csv").write_text("point,axis\nbase_s1,\n")
    from dem_contract.synthetic import write_case
    import pandas as pd
    for name, column, row, value in (("fabric_50", "A_xy", 40, 50.0), ("strain_jump", "strain", 40, None)):
        case = write_case(d / f"{name}_s1", default_params(), protocols=("heaviside",))
        run = pd.read_csv(case / "heaviside.csv")
        if value is None:
            run.loc[row:, column] += 0.3    # a strain jump of 0.3 between data rows 40 and 41
        else:
            run.loc[row, column] = value    # data row 41
        run.to_csv(case / "heaviside.csv", index=False)
    return d


SIM = ["-m", "model", "simulate"]
PREDICT = ["-m", "compare", "predict"]
STUDY = ["-m", "dem_study", "analyse", "--heaviside-strain", "1", "--campaign-I", "0.001"]

# (id, arguments with {d} for the inputs folder, strings the message must contain)
CASES = [
    ("model: malformed params YAML gives file and line",
     SIM + ["--params", "{d}/malformed.yaml"], ["malformed.yaml:3:", "malformed YAML"]),
    ("model: missing params file", SIM + ["--params", "{d}/absent.yaml"], ["absent.yaml", "not found"]),
    ("model: params file is a directory", SIM + ["--params", "{d}/a_directory"], ["a_directory", "directory"]),
    ("model: params version one", SIM + ["--params", "{d}/version_one.yaml"], ["version_one.yaml", "'version'"]),
    ("model: unknown params key", SIM + ["--params", "{d}/bad_key.yaml"], ["bad_key.yaml", "Xc", "model1"]),
    ("model: missing --table file", SIM + ["--protocol", "table", "--table", "{d}/absent.csv"],
     ["absent.csv", "not found"]),
    ("model: --table is a directory", SIM + ["--protocol", "table", "--table", "{d}/a_directory"],
     ["a_directory", "directory"]),
    ("model: --table row cut off", SIM + ["--protocol", "table", "--table", "{d}/cut_table.csv"],
     ["cut_table.csv", "gammadot", "row 3"]),
    ("model: --table without gammadot", SIM + ["--protocol", "table", "--table", "{d}/no_rate.csv"],
     ["no_rate.csv", "gammadot"]),
    ("model: --protocol table without --table", SIM + ["--protocol", "table"], ["--table"]),
    ("model: --out under a file", SIM + ["--out", "{d}/a_file/out"], ["a_file/out"]),
    ("calibrate: missing DEM dir", ["-m", "calibrate", "--dem", "{d}/absent_case", "--out", "{d}/cal"],
     ["absent_case", "not found"]),
    ("calibrate: DEM dir without runs", ["-m", "calibrate", "--dem", "{d}/a_directory", "--out", "{d}/cal"],
     ["a_directory/preshear.csv", "not found"]),
    ("calibrate: one row with A_xy = 50",
     ["-m", "calibrate", "--dem", "{d}/fabric_50_s1", "--protocols", "heaviside", "--out", "{d}/cal"],
     ["fabric_50_s1/heaviside.csv", "'A_xy' = 50 at data row 41", "[-0.5, 0.5]"]),
    ("calibrate: a strain jump inside a run",
     ["-m", "calibrate", "--dem", "{d}/strain_jump_s1", "--protocols", "heaviside", "--out", "{d}/cal"],
     ["strain_jump_s1/heaviside.csv", "strain jumps", "data rows 40 and 41"]),
    ("calibrate: --out under a file", ["-m", "calibrate", "--dem", "{d}/a_directory", "--out", "{d}/a_file/cal"],
     ["a_file/cal"]),
    ("compare: malformed params YAML gives file and line",
     PREDICT + ["--dem", "{d}/a_directory", "--params", "{d}/malformed.yaml", "--out", "{d}/cmp"],
     ["malformed.yaml:3:"]),
    ("compare: params is a directory",
     PREDICT + ["--dem", "{d}/a_directory", "--params", "{d}/a_directory", "--out", "{d}/cmp"],
     ["a_directory", "directory"]),
    ("compare: params version one",
     PREDICT + ["--dem", "{d}/a_directory", "--params", "{d}/version_one.yaml", "--out", "{d}/cmp"],
     ["version_one.yaml", "'version'"]),
    ("compare: missing DEM dir",
     PREDICT + ["--dem", "{d}/absent_case", "--params", "{d}/good.yaml", "--out", "{d}/cmp"],
     ["absent_case", "not found"]),
    ("compare: missing errors table",
     ["-m", "compare", "heldout", "--errors", "{d}/absent.csv", "--out", "{d}/h.csv"], ["absent.csv"]),
    ("compare: synthetic under a file", ["-m", "compare", "synthetic", "--out", "{d}/a_file/dem"], ["a_file/dem"]),
    ("dem_study: missing points table",
     STUDY + ["--points", "{d}/absent.csv", "--dem-dir", "{d}/a_directory", "--out", "{d}/st"],
     ["absent.csv", "--points"]),
    ("dem_study: missing DEM dir",
     STUDY + ["--points", "{d}/points.csv", "--dem-dir", "{d}/absent_dem", "--out", "{d}/st"],
     ["absent_dem", "--dem-dir"]),
    ("dem_study: malformed config YAML gives file and line",
     ["-m", "dem_study", "estimate", "--configfile", "{d}/malformed.yaml"], ["malformed.yaml:3:"]),
    ("dem_study: missing config file",
     ["-m", "dem_study", "estimate", "--configfile", "{d}/absent.yaml"], ["absent.yaml", "not found"]),
    ("dem_study: config without the accuracy block",
     ["-m", "dem_study", "estimate", "--configfile", "{d}/good.yaml"], ["good.yaml", "accuracy"]),
]


#: The function each package's ``__main__`` calls with the command line's arguments.
MAINS = {"model": "model.cli", "calibrate": "calibrate.__main__", "compare": "compare.cli", "dem_study": "dem_study.cli"}
#: The rows run as a process of their own: the first of each package.
IN_A_PROCESS = {next(c[0] for c in CASES if c[1][1] == package) for package in MAINS}


@pytest.mark.parametrize("argv, needles, own_process", [(*c[1:], c[0] in IN_A_PROCESS) for c in CASES],
                         ids=[c[0] for c in CASES])
def test_bad_input_exits_2_with_one_line_naming_the_file(inputs, argv, needles, own_process):
    args = [a.format(d=inputs) for a in argv]
    if own_process:
        proc = subprocess.run([sys.executable, *args], cwd=ROOT, capture_output=True, text=True, timeout=120)
    else:
        proc = run_main(MAINS[args[1]], args[2:], package=args[1])
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    message = lines[0]
    for needle in needles:
        assert needle in message, message
