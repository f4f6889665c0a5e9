"""The ``bladelab`` command line.

Each workflow contributes a sub-command module in this package (``bladelab.cli.trial``,
``bladelab.cli.blade``, ...) that defines ``register(app)``. Errors derived from
:class:`~bladelab.errors.BladelabError` are printed as one line and exit with status 2; ``--debug``
shows the traceback instead.
"""

from __future__ import annotations

import importlib
import signal
import sys
import threading

import typer

from bladelab import __version__
from bladelab.errors import BladelabError

# Sub-command modules, in help order. Each defines ``register(app: typer.Typer) -> None``.
_COMMAND_MODULES: tuple[str, ...] = ("trial", "blade", "simulate", "runner", "identify", "predict", "example", "report",
                                     "design")

app = typer.Typer(
    name="bladelab",
    help="Biomechanics of running-specific prostheses: characterise, predict and design blades.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
    rich_markup_mode=None,  # help text is plain: units in brackets such as [mm²/mm] stay visible
)

_state = {"debug": False}


def _version_callback(value: bool) -> None:
    if value:
        typer.echo(f"bladelab {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    debug: bool = typer.Option(False, "--debug", help="Show full tracebacks on errors."),
    version: bool = typer.Option(
        False, "--version", callback=_version_callback, is_eager=True, help="Print the version."
    ),
) -> None:
    _state["debug"] = _state["debug"] or debug


for _name in _COMMAND_MODULES:
    importlib.import_module(f"bladelab.cli.{_name}").register(app)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``bladelab`` command; returns the exit status.

    Usage errors exit with 2 (typer's own handling); a :class:`BladelabError` prints one line
    ``error: ...`` on stderr and exits with 2; ``--debug`` re-raises it with its traceback.
    """
    args = sys.argv[1:] if argv is None else list(argv)
    # --debug is accepted anywhere on the line (before or after the sub-command)
    _state["debug"] = "--debug" in args
    args = [a for a in args if a != "--debug"]
    _state["terminated"] = False
    previous = _catch_sigterm()
    try:
        app(args=args, prog_name="bladelab")
    except SystemExit as exit_:
        if _state["terminated"]:  # click turned the interrupt into an exit
            return _interrupted()
        code = exit_.code
        return code if isinstance(code, int) else (0 if code is None else 1)
    except BladelabError as err:
        if _state["debug"]:
            raise
        typer.echo(f"error: {err}", err=True)
        return 2
    except KeyboardInterrupt:
        return _interrupted()
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)
    return 0


def _interrupted() -> int:
    """Say how the run was stopped; the exit status of SIGTERM (143) or Ctrl-C (130)."""
    if _state["terminated"]:
        typer.echo("terminated", err=True)
        return 143
    typer.echo("interrupted", err=True)
    return 130


def _raise_terminated(signum, frame) -> None:
    """SIGTERM (``kill``, a job scheduler) raised as an interrupt, so the same clean-up runs as
    for Ctrl-C: worker processes are stopped and written checkpoints stay valid."""
    _state["terminated"] = True
    raise KeyboardInterrupt


def _catch_sigterm():
    """Install the SIGTERM handler (main thread only); returns the previous handler or None."""
    if threading.current_thread() is not threading.main_thread():
        return None
    return signal.signal(signal.SIGTERM, _raise_terminated)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
