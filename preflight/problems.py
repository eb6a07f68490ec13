"""One line per problem of a config: ``config error: <key> = <value>: <what is wrong> (allowed: <what would do>)``."""
from __future__ import annotations

from dem_contract.labels import format_number


def value_text(x) -> str:
    """A config value as the problem line shows it: numbers as labels print them, text quoted."""
    return format_number(x) if isinstance(x, float) else repr(x) if isinstance(x, str) else str(x)


def problem(key: str, value, why: str, allowed: str | None = None, shown: str | None = None) -> str:
    """One line: ``config error: key = value: why (allowed: ...)``; ``shown`` replaces the value's text."""
    text = f"config error: {key} = {value_text(value) if shown is None else shown}: {why}"
    return text + (f" (allowed: {allowed})" if allowed else "")
