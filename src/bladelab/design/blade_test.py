"""The virtual compression test of a blade at several alignments, loaded to body weight.

:func:`virtual_blade_test` runs :func:`~bladelab.design.compression.compression_test` at each
alignment angle up to a largest clamp displacement, with the load m·g of a runner of body mass
m (standard gravity) as the reference load of the stiffness at body weight. A blade that cannot
compress with its support held (fewer than two compliant joints between clamp and support) is
tested with its tip free, and the result says so. ``bladelab blade test`` prints it;
:func:`plot_blade_test` draws its force–displacement curves.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from matplotlib.figure import Figure

from bladelab.blade import load_blade
from bladelab.blade.model import BladeModel
from bladelab.design import defaults
from bladelab.design.compression import (
    CompressionTestResult,
    compression_test,
    vertical_stiffness,
)
from bladelab.design.plots import save_figure
from bladelab.errors import ModelError, SpecError
from bladelab.units import body_weight

__all__ = ["BladeTestResult", "plot_blade_test", "virtual_blade_test"]


@dataclass(frozen=True)
class BladeTestResult:
    """The compression tests of one blade.

    Attributes
    ----------
    blade
        The blade's name.
    tip
        Tip condition of the tests: ``"held"`` or ``"free"``.
    tip_freed
        The tip was asked to be held, but the blade cannot compress so: tested free.
    body_mass_kg, load_N
        Body mass [kg] and its weight m·g [N], the reference load.
    tests
        One test per alignment, in the order given.
    """

    blade: str
    tip: str
    tip_freed: bool
    body_mass_kg: float
    load_N: float
    tests: tuple[CompressionTestResult, ...]

    def to_dict(self) -> dict:
        """JSON-ready: the curves included, a load not reached as null."""
        def clean(v):
            if isinstance(v, float) and not math.isfinite(v):
                return None
            if isinstance(v, dict):
                return {k: clean(x) for k, x in v.items()}
            if isinstance(v, list):
                return [clean(x) for x in v]
            return v

        return clean({"blade": self.blade, "body_mass_kg": self.body_mass_kg,
                      "load_N": self.load_N, "tests": [t.to_dict() for t in self.tests]})


def virtual_blade_test(
    blade: str | Path | BladeModel,
    *,
    category: str | None = None,
    alignments_deg: Sequence[float] = defaults.COMPRESSION_ALIGNMENTS_DEG,
    body_mass_kg: float = defaults.BODY_MASS_KG,
    max_displacement_m: float = defaults.COMPRESSION_MAX_DISPLACEMENT_M,
    tip: str = "held",
    n_steps: int = defaults.COMPRESSION_STEPS,
) -> BladeTestResult:
    """Compression tests of ``blade`` (a built blade, a built-in blade's name or a blade spec
    file, of stiffness ``category``) at each alignment [deg], up to ``max_displacement_m``
    [m] in ``n_steps`` steps, with the weight of ``body_mass_kg`` [kg] as reference load (module
    docstring). A test that does not reach the load reports its stiffness there as NaN.

    Raises
    ------
    SpecError
        A body mass that is not a positive number; no alignment.
    """
    if not (body_mass_kg > 0 and math.isfinite(body_mass_kg)):
        raise SpecError(f"body mass must be > 0 kg, got {body_mass_kg}", where="body_mass_kg")
    if len(alignments_deg) == 0:
        raise SpecError("no alignment angle given", where="alignments_deg")
    model = blade if isinstance(blade, BladeModel) else load_blade(blade, category=category).build()
    load = body_weight(body_mass_kg)
    freed = False
    if tip == "held":
        try:
            vertical_stiffness(model, alignment_deg=alignments_deg[0], tip="held")
        except ModelError:
            tip, freed = "free", True
    tests = []
    for a in alignments_deg:
        try:
            r = compression_test(model, max_displacement=max_displacement_m, n_steps=n_steps,
                                 load=load, alignment_deg=a, tip=tip)
        except SpecError as err:
            if err.where != "load":
                raise
            r = compression_test(model, max_displacement=max_displacement_m, n_steps=n_steps,
                                 alignment_deg=a, tip=tip)
        tests.append(r)
    return BladeTestResult(model.name, tip, freed, float(body_mass_kg), load, tuple(tests))


def plot_blade_test(result: BladeTestResult, path: str | Path) -> Path:
    """Force [N] against clamp displacement [mm], one curve per alignment, and the reference
    load; written (atomically) to ``path`` in the format of its suffix."""
    fig = Figure(figsize=(5, 4))
    ax = fig.subplots()
    for r in result.tests:
        ax.plot(r.displacement * 1e3, r.force, label=f"{r.alignment_deg:+g}°")
    ax.axhline(result.load_N, color="0.5", ls="--", lw=0.8, label="body weight")
    ax.set_xlabel("clamp displacement [mm]")
    ax.set_ylabel("vertical force [N]")
    ax.set_title(f"{result.blade}: virtual compression test")
    ax.legend(title="alignment")
    fig.tight_layout()
    return save_figure(fig, path)
