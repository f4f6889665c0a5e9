"""A self-contained HTML report made of composable sections.

Workflows add their own sections (identification, prediction, design) to one :class:`Report`;
:meth:`Report.write` renders ``index.html`` from the package's Jinja2 template with every figure
embedded as a base64 PNG and every interactive block (:class:`EmbeddedHTML`, e.g. an animation:
inline SVG and JavaScript, nothing loaded from elsewhere) in the page, so that it opens offline,
alone; writes each table also as CSV under ``tables/`` and any attached files
(:meth:`Report.add_file`), appends a "Settings, versions and seed" section, and does it
atomically: the whole folder is built under a temporary name beside the target and renamed
into place.
"""

from __future__ import annotations

import base64
import contextlib
import dataclasses
import datetime as _dt
import hashlib
import io
import json
import os
import platform
import re
import shutil
import tempfile
from collections.abc import Callable, Mapping, Sequence
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from bladelab.errors import BladelabError

__all__ = [
    "EmbeddedFigure",
    "EmbeddedHTML",
    "Report",
    "ReportTable",
    "Section",
    "environment_versions",
]

_PACKAGES = ("bladelab", "numpy", "scipy", "pandas", "numba", "mujoco", "matplotlib", "cma")


@dataclasses.dataclass(frozen=True)
class EmbeddedFigure:
    """A rendered figure: PNG bytes as base64, a caption and alternative text."""

    png_base64: str
    caption: str
    alt: str
    width_px: int
    height_px: int

    @classmethod
    def from_matplotlib(cls, fig: Figure, *, caption: str = "", dpi: int = 144) -> EmbeddedFigure:
        """Render ``fig`` to PNG (``dpi`` dots per inch) and embed it."""
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=dpi, facecolor="white")
        w, h = fig.get_size_inches() * dpi
        titles = [ax.get_title() for ax in fig.axes if ax.get_visible() and ax.get_title()]
        alt = caption or "; ".join(titles) or "figure"
        return cls(base64.b64encode(buf.getvalue()).decode("ascii"), caption, alt, int(w), int(h))


@dataclasses.dataclass(frozen=True)
class EmbeddedHTML:
    """A self-contained block of HTML placed in the page as it is (not escaped), e.g. an
    animation: inline SVG and JavaScript only, nothing loaded from elsewhere (the page must
    open offline). Its scripts must not rely on ids of other blocks."""

    html: str
    caption: str = ""


@dataclasses.dataclass(frozen=True, eq=False)
class ReportTable:
    """A table shown in the page and written as ``tables/<name>.csv``.

    ``frame`` is displayed; ``csv`` (default ``frame``) is what goes into the CSV file, so a
    display layout (e.g. ``"10.27 ± 2.28"``) can sit beside plain numbers.
    """

    title: str
    frame: pd.DataFrame
    name: str
    csv: pd.DataFrame | None = None


@dataclasses.dataclass(eq=False)
class Section:
    """One titled part of the report: text paragraphs, HTML blocks, figures and tables, in that
    order."""

    title: str
    anchor: str
    text: list[str]
    figures: list[EmbeddedFigure]
    tables: list[ReportTable]
    blocks: list[EmbeddedHTML] = dataclasses.field(default_factory=list)


def _slug(text: str) -> str:
    slug = re.sub(r"[^a-z0-9]+", "-", text.lower()).strip("-")
    return slug or "section"


#: The longest table name [characters]: its CSV file name must stay well below the 255 bytes
#: file systems allow, however long the table's title.
MAX_TABLE_NAME = 120


def _table_name(anchor: str, title: str) -> str:
    """The file-safe name of a table (its CSV is ``tables/<name>.csv``): the section's anchor
    and the title's slug, cut to :data:`MAX_TABLE_NAME` characters with a hash of the whole
    name where it is longer (so that two long titles stay apart)."""
    name = f"{anchor}-{_slug(title)}"
    if len(name) <= MAX_TABLE_NAME:
        return name
    digest = hashlib.sha1(name.encode("utf-8")).hexdigest()[:8]
    return f"{name[:MAX_TABLE_NAME - 9].rstrip('-')}-{digest}"


def _format_cell(value: Any) -> str:
    if isinstance(value, bool | np.bool_):
        return "yes" if value else "no"
    if isinstance(value, float | np.floating):
        if not np.isfinite(value):
            return "–"
        if value != 0 and (abs(value) < 1e-3 or abs(value) >= 1e5):
            return f"{value:.3g}"
        return f"{value:.4g}" if abs(value) < 1 else f"{value:.2f}"
    return str(value)


def environment_versions() -> dict[str, str]:
    """Python, platform and the versions of bladelab's main dependencies."""
    out = {"python": platform.python_version(), "platform": platform.platform()}
    for pkg in _PACKAGES:
        try:
            out[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            out[pkg] = "not installed"
    return out


def _flatten(settings: Mapping[str, Any], prefix: str = "") -> dict[str, str]:
    flat: dict[str, str] = {}
    for key, value in settings.items():
        name = f"{prefix}{key}"
        if isinstance(value, Mapping):
            flat.update(_flatten(value, prefix=f"{name}."))
        else:
            flat[name] = json.dumps(value, default=str) if not isinstance(value, str) else value
    return flat


class Report:
    """An HTML report built from sections.

    Parameters
    ----------
    title
        Page title.
    subtitle
        One line under the title (e.g. the study name), optional.
    settings
        Settings that produced the results (nested mappings are flattened to dotted keys);
        shown in the closing "Settings, versions and seed" section and written to
        ``settings.json``.
    seed
        The random seed used, shown in the same section.

    Examples
    --------
    >>> report = Report("Blade characterisation", settings={"pso": {"particles": 20}}, seed=1)
    >>> report.add_section("Stiffness", figures=[fig], tables=[("K* per group", df)])
    >>> report.write(study_dir / "report")  # -> study_dir/report/index.html
    """

    def __init__(
        self,
        title: str,
        *,
        subtitle: str | None = None,
        settings: Mapping[str, Any] | None = None,
        seed: int | None = None,
    ) -> None:
        self.title = title
        self.subtitle = subtitle
        self.settings = dict(settings or {})
        self.seed = seed
        self.sections: list[Section] = []
        self.files: dict[str, Callable[[Path], object]] = {}

    def add_section(
        self,
        title: str,
        *,
        figures: Sequence[Figure | tuple[str, Figure]] = (),
        tables: Sequence[pd.DataFrame | tuple[str, pd.DataFrame] | ReportTable] = (),
        text: str | None = None,
        html: Sequence[EmbeddedHTML] = (),
    ) -> Section:
        """Append a section and return it.

        Parameters
        ----------
        title
            Section heading (also its anchor and the prefix of its CSV file names).
        figures
            Matplotlib figures, or ``(caption, figure)`` pairs; rendered now and closed.
        tables
            DataFrames, ``(title, DataFrame)`` pairs or :class:`ReportTable` objects.
        text
            Plain text; blank lines separate paragraphs (HTML is escaped).
        html
            Self-contained HTML blocks (:class:`EmbeddedHTML`), shown after the text.
        """
        anchor = _slug(title)
        taken = {s.anchor for s in self.sections}
        base, i = anchor, 2
        while anchor in taken:
            anchor, i = f"{base}-{i}", i + 1
        embedded = []
        for item in figures:
            caption, fig = item if isinstance(item, tuple) else ("", item)
            if not isinstance(fig, Figure):
                raise BladelabError(
                    f"figure is a {type(fig).__name__}, not a matplotlib Figure",
                    where=f"report section {title!r}",
                )
            embedded.append(EmbeddedFigure.from_matplotlib(fig, caption=caption))
            fig.clear()
        rendered = []
        names = {t.name for s in self.sections for t in s.tables}
        for k, item in enumerate(tables, start=1):
            if isinstance(item, ReportTable):
                table = item
            else:
                ttitle, frame = item if isinstance(item, tuple) else (f"Table {k}", item)
                table = ReportTable(ttitle, frame, _table_name(anchor, ttitle))
            name, j = table.name, 2
            while name in names:
                name, j = f"{table.name}-{j}", j + 1
            names.add(name)
            rendered.append(dataclasses.replace(table, name=name))
        paragraphs = [p.strip() for p in re.split(r"\n\s*\n", text or "") if p.strip()]
        for block in html:
            if not isinstance(block, EmbeddedHTML):
                raise BladelabError(
                    f"HTML block is a {type(block).__name__}, not an EmbeddedHTML",
                    where=f"report section {title!r}",
                )
        section = Section(title, anchor, paragraphs, embedded, rendered, list(html))
        self.sections.append(section)
        return section

    def add_file(self, name: str, write: Callable[[Path], object]) -> str:
        """Attach a file to the report: ``write(path)`` is called by :meth:`write` to create
        ``name`` (a relative path such as ``export/run/grf.mot``) inside the report folder, as
        part of its atomic assembly. Returns ``name``, for a link from the page."""
        parts = Path(name).parts
        if not parts or Path(name).is_absolute() or ".." in parts or parts[0] in (
            "index.html", "tables", "settings.json"
        ):
            raise BladelabError(f"cannot attach a file named {name!r}",
                                hint="use a relative path inside the report folder")
        self.files[Path(name).as_posix()] = write
        return Path(name).as_posix()

    def _settings_section(self, created: str) -> Section:
        versions = environment_versions()
        rows = [("seed", "none" if self.seed is None else str(self.seed)), ("created", created)]
        rows += list(_flatten(self.settings).items())
        settings = pd.DataFrame(rows, columns=["setting", "value"])
        vers = pd.DataFrame(list(versions.items()), columns=["package", "version"])
        return Section(
            "Settings, versions and seed",
            "settings-versions-and-seed",
            ["The settings, random seed and software that produced this report."],
            [],
            [
                ReportTable("Settings and seed", settings, "settings"),
                ReportTable("Software versions", vers, "versions"),
            ],
        )

    def write(self, out_dir: str | Path) -> Path:
        """Write ``out_dir/index.html``, ``out_dir/tables/*.csv`` and ``settings.json``.

        The folder is assembled under a temporary name beside ``out_dir`` and renamed into
        place; an existing report folder is replaced only once the new one is complete.

        Returns
        -------
        pathlib.Path
            The path of ``index.html``.
        """
        from jinja2 import Environment, PackageLoader, select_autoescape

        out_dir = Path(out_dir)
        out_dir.parent.mkdir(parents=True, exist_ok=True)
        created = _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%d %H:%M UTC")
        sections = [*self.sections, self._settings_section(created)]
        env = Environment(
            loader=PackageLoader("bladelab.report", "templates"),
            autoescape=select_autoescape(["html", "j2"]),
            trim_blocks=True,
            lstrip_blocks=True,
        )
        env.filters["cell"] = _format_cell
        html = env.get_template("report.html.j2").render(
            title=self.title, subtitle=self.subtitle, created=created, sections=sections
        )
        tmp = Path(tempfile.mkdtemp(prefix=f".{out_dir.name}.", suffix=".part", dir=out_dir.parent))
        try:
            (tmp / "tables").mkdir()
            for section in sections:
                for table in section.tables:
                    csv = table.frame if table.csv is None else table.csv
                    csv.to_csv(tmp / "tables" / f"{table.name}.csv", index=False)
            (tmp / "settings.json").write_text(
                json.dumps(
                    {
                        "title": self.title,
                        "created": created,
                        "seed": self.seed,
                        "settings": self.settings,
                        "versions": environment_versions(),
                    },
                    indent=2,
                    default=str,
                )
                + "\n",
                encoding="utf-8",
            )
            for name, write_file in self.files.items():
                (tmp / name).parent.mkdir(parents=True, exist_ok=True)
                write_file(tmp / name)
            (tmp / "index.html").write_text(html, encoding="utf-8")
            os.chmod(tmp, 0o755)
            old = None
            if out_dir.exists():
                old = out_dir.with_name(f".{out_dir.name}.old-{os.getpid()}")
                os.replace(out_dir, old)
            try:
                os.replace(tmp, out_dir)
            except OSError:
                if old is not None:
                    os.replace(old, out_dir)
                raise
            if old is not None:
                shutil.rmtree(old, ignore_errors=True)
        except BaseException:
            with contextlib.suppress(OSError):
                shutil.rmtree(tmp)
            raise
        return out_dir / "index.html"
