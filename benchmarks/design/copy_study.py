"""Copy a predicted-gait design study's folder for committing: every file but the report, the
strides without their IPOPT multipliers (a quarter of a 100-interval stride's size; a resumed
pass starts from their primal values), and without the ``.previous`` and ``.best_iterate``
strides a solve replaced or gave up on. The continuation steps of the first design are kept.
Copied onto an earlier copy, a run or stride file the study no longer has is removed (a
settling pass deletes a changed design's run file so that its responses are read back from
the new stride: a stale one left behind would keep the old responses).

Usage (repository root)::

    .venv/bin/python benchmarks/design/copy_study.py /tmp/STUDY benchmarks/design/NAME
"""

from __future__ import annotations

import argparse
import json
import shutil
from pathlib import Path

SKIPPED = (".previous.json", ".best_iterate.json")


def copy_study(src: Path, dst: Path) -> int:
    """Copy ``src`` to ``dst`` as the module docstring says; returns the strides copied."""
    if not (src / "study.json").is_file():
        raise SystemExit(f"{src}: not a design study folder (no study.json)")
    dst.mkdir(parents=True, exist_ok=True)
    strides = 0
    for path in sorted(src.rglob("*")):
        rel = path.relative_to(src)
        if path.is_dir() or rel.parts[0] == "report" or path.name.endswith(SKIPPED):
            continue
        out = dst / rel
        out.parent.mkdir(parents=True, exist_ok=True)
        if rel.parts[0] == "strides" and path.suffix == ".json":
            data = json.loads(path.read_text())
            data["multipliers"] = None
            out.write_text(json.dumps(data))
            strides += 1
        else:
            shutil.copy2(path, out)
    for folder in ("runs", "strides"):
        for path in sorted((dst / folder).rglob("*.json")):
            if not (src / path.relative_to(dst)).is_file():
                path.unlink()
    return strides


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("src", type=Path)
    parser.add_argument("dst", type=Path)
    args = parser.parse_args()
    print(f"{copy_study(args.src, args.dst)} strides copied to {args.dst}")


if __name__ == "__main__":
    main()
