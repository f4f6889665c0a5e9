"""Run bladelab's benchmarks and assemble ``benchmarks/RESULTS.md``.

Each ``benchmarks/bench_<topic>.py`` defines ``run() -> str`` returning a Markdown section.
The section is written to ``benchmarks/results/<topic>.md`` together with the machine and the
date it was measured on; ``RESULTS.md`` is the concatenation of all sections, so running one
benchmark (``python benchmarks/run.py trial``) keeps the others' last results.
"""

from __future__ import annotations

import datetime as _dt
import importlib.util
import os
import platform
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
RESULTS_DIR = HERE / "results"


def machine_line() -> str:
    """One line naming the machine, Python and date."""
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    date = _dt.datetime.now().strftime("%Y-%m-%d %H:%M")
    return (
        f"_Measured {date} on {cpu}, {os.cpu_count()} cores, Python {platform.python_version()}, "
        f"{platform.system()} {platform.release()}._"
    )


def _load(path: Path):
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    sys.path.insert(0, str(HERE))
    spec.loader.exec_module(module)
    return module


def main(argv: list[str]) -> int:
    benches = sorted(HERE.glob("bench_*.py"))
    if argv:
        benches = [b for b in benches if b.stem.removeprefix("bench_") in argv]
    RESULTS_DIR.mkdir(exist_ok=True)
    for bench in benches:
        topic = bench.stem.removeprefix("bench_")
        print(f"[bench] {topic} ...", flush=True)
        section = _load(bench).run().rstrip() + "\n\n" + machine_line() + "\n"
        tmp = RESULTS_DIR / f".{topic}.md.part"
        tmp.write_text(section, encoding="utf-8")
        tmp.replace(RESULTS_DIR / f"{topic}.md")
        print(section)
    sections = [p.read_text(encoding="utf-8") for p in sorted(RESULTS_DIR.glob("*.md"))]
    text = (
        "# bladelab benchmark results\n\n"
        "Written by `make bench` (`python benchmarks/run.py [topic ...]`). Each section says the "
        "machine and date it was measured on. Speed targets live here, never in tests.\n\n"
        + "\n".join(sections)
    )
    (HERE / "RESULTS.md").write_text(text, encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
