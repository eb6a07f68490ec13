"""A stage's extra command-line options, from a config string, as a list of words.

``calibration.options`` and ``compare.options`` hold options of ``python -m calibrate``
and ``python -m compare predict``. The rules pass them as separate arguments: the
string split into words as a shell would split it (``shlex.split``), each word then
quoted by Snakemake's ``{params.options:q}``, so no word of a config file is ever read
by a shell as code. ``given`` says what the words set, for a rule that follows one of
them (pole_start.smk takes calibrate's fit budget) and for the pre-flight, which checks
every word before any rule sees it (preflight/options.py).
"""
from __future__ import annotations

import shlex


def words(config: dict, key: str) -> list[str]:
    """The options string at ``key`` (e.g. ``"calibration.options"``) split into words; [] when unset.

    Raises ValueError (shlex's) for an unclosed quote: the pre-flight names it first.
    """
    section, name = key.split(".")
    return shlex.split((config.get(section) or {}).get(name) or "")


def is_option(word: str) -> bool:
    """A word that names an option (``-x``, ``--name``, ``--name=value``), not a value such as ``-1e-3``."""
    if not word.startswith("-") or word == "-":
        return False
    try:
        float(word)
    except ValueError:
        return True
    return False


def option_name(word: str) -> str:
    """The option a word names: ``--name=value`` -> ``--name``."""
    return word.split("=", 1)[0]


def given(argv: list[str]) -> dict[str, list[str]]:
    """Option -> the words after it up to the next option (``--name=value`` gives ``[value]``).

    Examples
    --------
    >>> given(["--route2-evals=80", "--freeform-penalties", "1e-4", "1", "--no-figures"])
    {'--route2-evals': ['80'], '--freeform-penalties': ['1e-4', '1'], '--no-figures': []}
    """
    out: dict[str, list[str]] = {}
    current = None
    for word in argv:
        if is_option(word):
            current = option_name(word)
            out[current] = [word.split("=", 1)[1]] if "=" in word else []
        elif current is not None:
            out[current].append(word)
    return out


def given_int(argv: list[str], option: str, default: int) -> int:
    """The integer ``option`` is given in ``argv`` (its first value), else ``default``."""
    values = given(argv).get(option)
    return int(values[0]) if values else default
