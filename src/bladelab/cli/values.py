"""Option values the command line reads from text: comma-separated lists."""

from __future__ import annotations

from bladelab.errors import SpecError

__all__ = ["parse_list"]


def parse_list(text: str, what: str, conv=str, *, hint: str = "comma-separated") -> list:
    """A comma-separated option value as a list of ``conv`` values (empty items skipped);
    errors name the option ``what`` and give ``hint``."""
    try:
        items = [conv(t.strip()) for t in text.split(",") if t.strip()]
    except ValueError:
        raise SpecError(f"cannot read {what} {text!r}", where=what, hint=hint) from None
    if not items:
        raise SpecError(f"no {what} given", where=what)
    return items
