"""Column layouts of a :class:`~bladelab.runner.model.RunnerModel`'s parameter arrays.

``contact_params`` has one row per contact (13 columns, ``CP_*``): site id, body id, radius or
x semi-axis [m], stiffness k [N/m^n], dissipation [s/m], friction [-], leg (0 = left/intact,
1 = right/prosthetic), is_blade (0/1), z semi-axis [m], law (``LAW_*``), exponent n, damping
[N·s/m] and transition width [m] (the smooth spring–damper's).

``joint_params`` has one row per dof (10 columns, ``JP_*``): ligament lower and upper limit
[rad], ligament stiffness [N·m/rad] and damping [N·m·s/rad], spring K [N·m/rad] and K2
[N·m/rad²], damping D while q̇ < 0 (``JP_SD``, a knee flexing) and while q̇ > 0 (``JP_SDX``,
extending) [N·m·s/rad]: equal for every joint but a hydraulic prosthetic knee; and a passive
moment ``A·exp(B·q)`` of the joint's capsule and ligaments within its range, amplitude A
[N·m] (``JP_EA``) and rate B [1/rad] (``JP_EB``), 0 where the joint has none.
"""

from __future__ import annotations

__all__ = [
    "CP_AZ", "CP_BLADE", "CP_BODY", "CP_C", "CP_DAMP", "CP_EXP", "CP_K", "CP_LAW", "CP_LEG",
    "CP_MU", "CP_RADIUS", "CP_SITE", "CP_WIDTH", "JP_COLUMNS", "JP_D", "JP_EA", "JP_EB",
    "JP_HI", "JP_K", "JP_LO", "JP_SD", "JP_SDX", "JP_SK", "JP_SK2", "LAW_HUNT_CROSSLEY",
    "LAW_SPRING_DAMPER",
]

# Columns of RunnerModel.contact_params.
CP_SITE, CP_BODY, CP_RADIUS, CP_K, CP_C, CP_MU, CP_LEG, CP_BLADE = range(8)
CP_AZ, CP_LAW, CP_EXP, CP_DAMP, CP_WIDTH = range(8, 13)
# Contact laws (column CP_LAW): Hunt–Crossley, smooth spring–damper.
LAW_HUNT_CROSSLEY, LAW_SPRING_DAMPER = 0, 1
# Columns of RunnerModel.joint_params (one row per dof).
JP_LO, JP_HI, JP_K, JP_D, JP_SK, JP_SK2, JP_SD, JP_SDX, JP_EA, JP_EB = range(10)
#: Columns of RunnerModel.joint_params.
JP_COLUMNS = JP_EB + 1
