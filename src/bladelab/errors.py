"""Errors that tell the user what is wrong, where, and how to fix it.

Every error raised on bad input is a :class:`BladelabError` (or a subclass). The CLI prints its
message and exits with status 2, without a traceback unless ``--debug`` is given.
"""

from __future__ import annotations

from pathlib import Path


class BladelabError(Exception):
    """Base class of all bladelab errors.

    Parameters
    ----------
    message
        What is wrong, in one sentence.
    file
        The file concerned, if any.
    where
        The channel, field, frame or parameter concerned, if any.
    hint
        How to fix it.
    """

    def __init__(
        self,
        message: str,
        *,
        file: str | Path | None = None,
        where: str | None = None,
        hint: str | None = None,
    ) -> None:
        self.message = message
        self.file = None if file is None else str(file)
        self.where = where
        self.hint = hint
        super().__init__(self._format())

    def _format(self) -> str:
        parts = []
        if self.file:
            parts.append(f"{self.file}: ")
        if self.where:
            parts.append(f"{self.where}: ")
        parts.append(self.message)
        if self.hint:
            parts.append(f" (hint: {self.hint})")
        return "".join(parts)


class InputFileError(BladelabError):
    """A file cannot be read: missing, not of the expected format, truncated."""


class DataError(BladelabError):
    """A file was read but its content is unusable: missing channel, gaps, NaN, no stance."""


class SpecError(BladelabError):
    """A specification (blade spec, study.yaml, parameter file) is invalid."""


class ModelError(BladelabError):
    """A model cannot be built from the given parameters."""


class SimulationError(BladelabError):
    """A simulation failed (diverged, produced non-finite values)."""


class OptimizationError(BladelabError):
    """An identification or optimisation was set up wrongly or failed."""
