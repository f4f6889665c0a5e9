"""The runner's passive knee and hip moments against Riener & Edrich (1999)'s measured ones.

Usage (repository root): ``.venv/bin/python benchmarks/human_body/passive_moments.py [BODY]``
(default ``human``; also ``seed001``). One line per pose, ankle at 0°: the model's moment /
people's [N·m] (``bladelab.runner.passive_moments``).
"""

from __future__ import annotations

import sys

from bladelab.runner import build_runner
from bladelab.runner.passive_moments import (
    passive_flexion_moment,
    riener_edrich_hip_moment,
    riener_edrich_knee_moment,
)

KNEE_POSES_DEG = [(k, h) for h in (0, 30) for k in (30, 60, 90, 120)]
HIP_POSES_DEG = [(k, h) for k in (0, 60) for h in (-20, 0, 30, 60)]


def main() -> None:
    body = sys.argv[1] if len(sys.argv) > 1 else "human"
    runner = build_runner("able", body=body)
    print(f"body {body}: passive moments [N·m], model / Riener & Edrich 1999 (ankle 0°)")
    for k, h in KNEE_POSES_DEG:
        model = passive_flexion_moment(runner, "knee", knee_deg=k, hip_deg=h)
        print(f"  knee flexion moment at knee {k:3d}°, hip {h:3d}°: {model:6.1f} / "
              f"{riener_edrich_knee_moment(k, h):6.1f}")
    for k, h in HIP_POSES_DEG:
        model = passive_flexion_moment(runner, "hip", knee_deg=k, hip_deg=h)
        print(f"  hip flexion moment at knee {k:3d}°, hip {h:3d}°: {model:6.1f} / "
              f"{riener_edrich_hip_moment(k, h):6.1f}")


if __name__ == "__main__":
    main()
