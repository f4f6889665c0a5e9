"""File input and output shared by every wing.

Output is atomic: written to a temporary name beside the target, then renamed, so a crash never
leaves a half-written file that looks complete. Input of JSON and YAML goes through
:func:`read_json` / :func:`read_yaml`, whose errors name the file (and the line and column of a
syntax error) as :class:`~bladelab.errors.InputFileError`.
"""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

from bladelab.errors import InputFileError, SpecError


def _umask() -> int:
    """The process's umask (read by setting it and setting it back)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_path(target: str | Path) -> Iterator[Path]:
    """Yield a temporary path in the target's folder; rename it to ``target`` on success.

    On an exception the temporary file is removed and the target is left untouched.
    """
    target = Path(target)
    if target.is_dir():
        raise InputFileError("is a folder, not a file name", file=target,
                             hint="give the path of the file to write (e.g. add a file name)")
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp_name = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".part", dir=target.parent)
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        yield tmp
        # mkstemp creates 0600; a finished file gets the mode any new file would (the umask)
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()
        raise


@contextlib.contextmanager
def atomic_open(target: str | Path, mode: str = "w", **kwargs: Any) -> Iterator[IO]:
    """Open a temporary file for writing; it becomes ``target`` only if the block succeeds."""
    with atomic_path(target) as tmp, open(tmp, mode, **kwargs) as fh:
        yield fh


def write_json(target: str | Path, obj: Any) -> None:
    """Write ``obj`` as indented JSON to ``target`` atomically."""
    with atomic_open(target, "w", encoding="utf-8") as fh:
        json.dump(obj, fh, indent=2, sort_keys=False)
        fh.write("\n")


def _read_text(path: Path, what: str, hint: str | None) -> str:
    if not path.is_file():
        raise InputFileError(f"{what} not found", file=path, hint=hint)
    try:
        return path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise InputFileError(f"cannot read the {what} ({type(err).__name__}: {err})",
                             file=path, hint=hint) from None


def read_json(path: str | Path, *, what: str = "JSON file", hint: str | None = None) -> Any:
    """The content of a JSON file; a missing, unreadable or invalid file raises
    :class:`~bladelab.errors.InputFileError` naming it (``what`` says what the file is)."""
    path = Path(path)
    text = _read_text(path, what, hint)
    try:
        return json.loads(text)
    except json.JSONDecodeError as err:
        raise InputFileError(f"not valid JSON: {err.msg} at line {err.lineno}, column {err.colno}",
                             file=path, hint=hint) from None


def read_yaml(path: str | Path, *, what: str = "YAML file", hint: str | None = None) -> Any:
    """The content of a YAML file (``safe_load``); errors as :func:`read_json`."""
    import yaml  # deferred: the CLI imports _io at start-up; few commands read YAML

    path = Path(path)
    text = _read_text(path, what, hint)
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
        problem = getattr(err, "problem", None) or str(err).splitlines()[0]
        raise InputFileError(f"not valid YAML: {problem}{where}", file=path, hint=hint) from None


def figure_format(path: str | Path, *, where: str = "--plot") -> str:
    """The image format of a figure path from its suffix (``.png`` when it has none); an
    unsupported suffix raises :class:`~bladelab.errors.SpecError` naming ``where`` and the
    formats matplotlib can write, before anything is drawn."""
    # deferred: the CLI imports _io at start-up; matplotlib takes ~0.5 s
    from matplotlib.backend_bases import FigureCanvasBase

    fmt = Path(path).suffix.lstrip(".").lower() or "png"
    supported = FigureCanvasBase.get_supported_filetypes()
    if fmt not in supported:
        raise SpecError(f"cannot write a figure as .{fmt}", file=path, where=where,
                        hint=f"use one of .{', .'.join(sorted(supported))} (e.g. .png)")
    return fmt
