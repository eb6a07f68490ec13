"""The extra options of calibrate and compare (``calibration.options``, ``compare.options``), checked before any job.

The rules pass the words of these strings as arguments (campaign/stage_options.py); the
schema lets through only words no shell reads specially. Here each word that names an
option must be an option of the program itself, written in full (argparse would read an
abbreviation such as ``--prot`` as ``--protocols``), and not one the workflow passes or
decides itself (``OWNED``): a second ``--protocols``, ``--out`` or ``--dem`` would silently
replace the rule's, and a calibration set ``all`` learnt from Heaviside runs alone would
still be called ``all``. The words then go through the program's own parser, which names a
bad value.
"""
from __future__ import annotations

import argparse
import contextlib
import io
import re

from campaign import stage_options
from campaign.stage_options import is_option, option_name

from .problems import problem

_HELP = "prints its help and writes no output"

#: config key -> (the command, {option the workflow passes or decides: who decides it}).
#: tests/test_shell_quoting.py checks that every option of the rule's command is here.
OWNED = {
    "calibration.options": ("python -m calibrate", {
        "--dem": "the calibration set's cases, calibration.sets",
        "--protocols": "the calibration set's protocols, calibration.sets",
        "--out": "results_dir: the rule writes <results_dir>/calibration/<set>/",
        "--freeform": "calibration.freeform",
        "--no-figures": "the rule declares the figures as its outputs",
        "-h": _HELP, "--help": _HELP,
    }),
    "compare.options": ("python -m compare predict", {
        "--dem": "the campaign's cases",
        "--params": "the calibration set's params.yaml",
        "--set": "the calibration set: one job per set",
        "--protocols": "the campaign's protocols, protocols:",
        "--train-cases": "the calibration set's cases, calibration.sets",
        "--train-protocols": "the calibration set's protocols, calibration.sets",
        "--figures": "the rule declares one figure per reversal kind of the campaign's protocols",
        "--out": "results_dir: the rule writes <results_dir>/compare/<set>/",
        "-h": _HELP, "--help": _HELP,
    }),
}


def _calibrate_parser():
    from calibrate.__main__ import parser

    return parser(), [], ["--dem", "d", "--out", "o"]


def _compare_parser():
    from compare.cli import build_parser

    return build_parser(), ["predict"], ["--dem", "d", "--params", "p", "--out", "o"]


#: config key -> () -> (the program's own parser, its sub-command's words, the options the rule always gives it)
PARSERS = {"calibration.options": _calibrate_parser, "compare.options": _compare_parser}


def option_strings(parser: argparse.ArgumentParser, command: list[str]) -> set[str]:
    """Every option string ``command --help`` lists (the first column of its option lines)."""
    text = io.StringIO()
    with contextlib.redirect_stdout(text), contextlib.suppress(SystemExit):
        parser.parse_args([*command, "--help"])
    return {option for line in text.getvalue().splitlines() if line.startswith("  -")
            for option in re.findall(r"(?<![\w-])--?[A-Za-z][\w-]*", re.split(r"\s{2,}", line.strip())[0])}


def argparse_error(parser: argparse.ArgumentParser, argv: list[str]) -> str | None:
    """argparse's own complaint about ``argv`` (its last stderr line), or None when it parses."""
    err = io.StringIO()
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            parser.parse_args(argv)
    except SystemExit:
        lines = err.getvalue().strip().splitlines()
        return lines[-1].split("error: ", 1)[-1] if lines else "not accepted"
    return None


def word_problem(word: str, options: set[str], owned: dict[str, str]) -> str | None:
    """Why an option word is refused (the workflow's own, abbreviated, unknown), or None."""
    name = option_name(word)
    if name in owned:
        return f"{name} is the workflow's own ({owned[name]}): a second one would replace the rule's"
    if name in options:
        return None
    starts = sorted(o for o in options | set(owned) if o.startswith(name))
    if starts:
        return f"{name} is not written in full (it abbreviates {' or '.join(starts)})"
    return f"{name} is not an option of the program"


def options_problems(config: dict) -> list[str]:
    """``calibration.options`` and ``compare.options``: only the program's own options, none the workflow owns,
    values its parser accepts; one line per refused option (or per parser complaint)."""
    out = []
    for key, (command, owned) in OWNED.items():
        section, name = key.split(".")
        value = (config.get(section) or {}).get(name) or ""
        argv = stage_options.words(config, key)
        if not argv:
            continue
        parser, sub_command, required = PARSERS[key]()
        options = option_strings(parser, sub_command) - set(owned)
        allowed = f"options of {command} --help except {', '.join(sorted(owned))}"
        found = [word_problem(w, options, owned) for w in argv if is_option(w)]
        out += [problem(key, value, why, allowed) for why in found if why]
        if not any(found):
            error = argparse_error(parser, [*sub_command, *required, *argv])
            if error:
                out.append(problem(key, value, error, allowed))
    return out
