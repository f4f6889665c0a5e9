"""The project speaks of itself only: no text file names the work sitting or the ticket that
made something ("<word> <number>"), in code, comments, docstrings, tests, docs, CLI help,
reports or stored results. Say what a thing is (or a date where one matters) instead."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
CHECKED = ("src", "docs", "tests", "benchmarks", "README.md")
SUFFIXES = {".py", ".md", ".json", ".csv", ".yaml", ".yml", ".txt", ".html", ".toml", ".cfg"}
SKIPPED_DIRS = {"__pycache__", ".ipynb_checkpoints"}

# built from parts so that this file does not match itself
_PLAIN = ("sess" + "ion", "is" + "sue", "sit" + "ting")
_WORDS = "|".join(_PLAIN)
# "<word> 17", "<Word> 20's", "<word> #21", "<words> 12–13", "<word>-15", "<word>_20"; a longer
# word that ends in one of the words is not a mention
PATTERN = re.compile(r"(?<![a-z])(" + _WORDS + r")s?[ _-]?#?[0-9]+", re.IGNORECASE)
# the word at the end of one line and its number at the start of the next (a wrapped sentence,
# also in a comment)
_WRAPPED = re.compile(r"(?<![a-z])(" + _WORDS + r")s?[ _-]?#?[ \t]*\r?\n"
                      r"[ \t]*(#:?|//|\*)?[ \t]*#?[0-9]", re.IGNORECASE)


def mentions(text: str) -> list[tuple[int, str]]:
    """(line number, line) of every line of ``text`` that names a sitting or a ticket by its
    number, alone or wrapped onto the next line."""
    low = text.lower()
    if not any(w in low for w in _PLAIN):  # fast: most files never use the words
        return []
    starts = [m.start() for m in (*PATTERN.finditer(text), *_WRAPPED.finditer(text))]
    if not starts:
        return []
    lines = text.splitlines()
    numbers = sorted({text.count("\n", 0, s) + 1 for s in starts})
    return [(n, lines[n - 1].strip()) for n in numbers]


def _files() -> list[Path]:
    out = []
    for name in CHECKED:
        path = ROOT / name
        if path.is_file():
            out.append(path)
            continue
        for f in sorted(path.rglob("*")):
            parts = f.relative_to(ROOT).parts
            if (f.is_file() and f.suffix.lower() in SUFFIXES
                    and not SKIPPED_DIRS.intersection(parts)
                    and not any(p.endswith(".egg-info") for p in parts)):  # build output
                out.append(f)
    return out


@pytest.mark.parametrize("line", [
    "(" + "session" + " 17)", "Is" + "sue 20's acceptance", "is" + "sue #21",
    "ses" + "sions 12–13", "is" + "sue-15", "def test_judges_is" + "sue_20():",
    "SES" + "SION 3", "# the method before is" + "sue\n# 16, which under-covered",
])
def test_checker_flags_a_numbered_mention(line):
    assert mentions(line), line


@pytest.mark.parametrize("line", [
    "the stable-gait acceptance", "an issue with 3 seeds", "tis" + "sue 3", "session of the runner",
    "issues: none", "one sitting; 4 runs", "the issue\nis 2 m/s",
])
def test_checker_passes_a_clean_line(line):
    assert not mentions(line), line


def test_the_project_names_no_sitting_or_ticket_by_number():
    files = _files()
    assert len(files) > 100  # the walk found the project
    bad = []
    for f in files:
        try:
            text = f.read_text(encoding="utf-8")
        except UnicodeDecodeError:
            continue  # not a text file
        bad += [f"{f.relative_to(ROOT)}:{n}: {line[:120]}" for n, line in mentions(text)]
    assert not bad, (f"{len(bad)} lines name a sitting or a ticket by number; say what the thing "
                     "is instead:\n" + "\n".join(bad))
