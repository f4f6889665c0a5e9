"""Options grouped by the method they belong to: the help's panels and the one check.

A command with several methods (``predict``, ``sweep``: reflex controller or collocation;
``design``: its evaluators) gives each option a help panel (typer's ``rich_help_panel``) and
lists its panels once, each with the methods its options belong to (:class:`Panel`). That
single tag serves twice:

- ``--help`` lists the options panel by panel (:class:`PanelCommand`, :class:`PanelGroup`;
  plain text, the same with or without rich installed, since the app's help is plain);
- :func:`refuse_other_methods` refuses an option given on the command line for a method it does
  not belong to, naming the option and its method.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import typer
from typer.core import TyperCommand, TyperGroup

from bladelab.errors import BladelabError, SpecError

__all__ = ["Panel", "PanelCommand", "PanelGroup", "refuse_other_methods", "renamed"]


@dataclass(frozen=True)
class Panel:
    """A group of options in ``--help``.

    Attributes
    ----------
    title
        The panel's heading (the options' ``rich_help_panel``).
    methods
        The methods its options belong to; None: every method.
    """

    title: str
    methods: tuple[str, ...] | None = None


def _format_panels(command, ctx, formatter) -> None:
    """Arguments, then the options under their panels' headings in order of first appearance;
    an option without a panel (``--help``) joins the first panel."""
    args, groups = [], {}
    for param in command.get_params(ctx):
        record = param.get_help_record(ctx)
        if record is None:
            continue
        if param.param_type_name == "argument":
            args.append(record)
            continue
        title = getattr(param, "rich_help_panel", None) or next(iter(groups), "Common")
        groups.setdefault(title, []).append(record)
    if args:
        with formatter.section("Arguments"):
            formatter.write_dl(args)
    for title, records in groups.items():
        with formatter.section(f"{title} options"):
            formatter.write_dl(records)


class PanelCommand(TyperCommand):
    """A command whose plain ``--help`` lists its options panel by panel."""

    def format_options(self, ctx, formatter) -> None:
        _format_panels(self, ctx, formatter)


class PanelGroup(TyperGroup):
    """A command group (options of its own and sub-commands) whose plain ``--help`` lists its
    options panel by panel, then its sub-commands."""

    def format_options(self, ctx, formatter) -> None:
        _format_panels(self, ctx, formatter)
        self.format_commands(ctx, formatter)


def _given(ctx: typer.Context, name: str) -> bool:
    """The parameter ``name`` was given on the command line (not its default)."""
    source = ctx.get_parameter_source(name)
    return source is not None and source.name == "COMMANDLINE"


def refuse_other_methods(ctx: typer.Context, chosen: str, panels: Sequence[Panel], *,
                         labels: Mapping[str, str],
                         hints: Mapping[str, str] | None = None) -> None:
    """Refuse the first option given on the command line whose panel belongs to other methods
    than ``chosen``: a :class:`SpecError` naming the option, the method(s) it belongs to and
    the one chosen. ``labels``: method -> how the command line selects it (``--method
    reflex``); ``hints``: option -> a hint added to its error."""
    methods = {p.title: p.methods for p in panels}
    for param in ctx.command.params:
        allowed = methods.get(getattr(param, "rich_help_panel", None))
        if allowed is None or chosen in allowed or not _given(ctx, param.name):
            continue
        option = next((o for o in param.opts if o.startswith("--")), param.opts[0])
        raise SpecError(f"only with {' or '.join(labels[m] for m in allowed)}, not with "
                        f"{labels[chosen]}", where=option, hint=(hints or {}).get(option))


def renamed(err: BladelabError, options: Mapping[str, str]) -> BladelabError:
    """``err`` with its ``where`` (a library argument or settings field, e.g. ``mesh_intervals``)
    replaced by the command-line option that set it (``options``: field -> option, e.g.
    ``--mesh``); a ``where`` of ``"field detail"`` keeps its detail. Unmapped: ``err``."""
    where = err.where or ""
    head, sep, tail = where.partition(" ")
    option = options.get(where) or (options.get(head) and f"{options[head]}{sep}{tail}")
    if not option:
        return err
    return type(err)(err.message, file=err.file, where=option, hint=err.hint)
