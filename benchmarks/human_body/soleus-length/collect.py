"""Gather strides of this record into ``records.jsonl`` (a measuring probe; changes nothing in
src).

Usage (repository root)::

    .venv/bin/python benchmarks/human_body/soleus-length/collect.py LABEL STRIDE.json [...]

Appends one line per stride: LABEL and ``../criteria.py``'s :func:`stride_record`. The strides
are read on the library's body as it is (the soleus at 0.25 m); a stride of another body gets
the numbers it stores, but its criteria are those of its own motion and forces either way.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from criteria import stride_record  # noqa: E402

from bladelab.predict.collocation.solution import CollocationSolution  # noqa: E402

HERE = Path(__file__).parent


def main() -> None:
    label, paths = sys.argv[1], sys.argv[2:]
    with (HERE / "records.jsonl").open("a", encoding="utf-8") as out:
        for path in paths:
            row = {"label": label, **stride_record(CollocationSolution.read(path))}
            out.write(json.dumps(row) + "\n")
            print(json.dumps(row))


if __name__ == "__main__":
    main()
