"""When independent optimisations of one cell agree: the cell has settled.

CMA-ES from a warm start finds one local optimum per seed; a reflex gait is chaotic, so two
seeds rarely end at the same cost. A cell has settled when its seeds' best costs
agree within 2 % and their speeds within 0.05 m/s. We read "its seeds agree" as: at least
:data:`MIN_SEEDS` seeds reach the best seed's cost within :data:`COST_TOLERANCE` (relative)
and its mean speed within :data:`SPEED_TOLERANCE` [m/s], all evaluated on the same copies (a
seed stuck in a worse optimum does not unsettle a cell that three others reproduce; a best
reached by one seed alone is not a result). Seed 001 ran six optimisations per cell until they
stopped changing (§2.2.2).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

__all__ = ["COST_TOLERANCE", "MIN_SEEDS", "SPEED_TOLERANCE", "SeedAgreement", "seed_agreement"]

MIN_SEEDS = 3
COST_TOLERANCE = 0.02
SPEED_TOLERANCE = 0.05  # m/s


@dataclass(frozen=True)
class SeedAgreement:
    """How the seeds of one cell agree.

    Attributes
    ----------
    seeds
        Seeds compared.
    agreeing
        Per seed: its cost within :data:`COST_TOLERANCE` of the best seed's and its speed
        within :data:`SPEED_TOLERANCE` [m/s] of the best's (the best agrees with itself).
    cost_spread_pct
        (largest − smallest) / smallest cost over all seeds [%].
    speed_spread_m_per_s
        Largest − smallest mean speed over all seeds [m/s].
    settled
        At least :data:`MIN_SEEDS` seeds agree.
    """

    seeds: int
    agreeing: tuple[bool, ...]
    cost_spread_pct: float
    speed_spread_m_per_s: float
    settled: bool

    def describe(self) -> str:
        """One sentence for a report."""
        n = sum(self.agreeing)
        verdict = "settled" if self.settled else "not settled"
        return (f"{n} of {self.seeds} seeds reach the best seed's cost within "
                f"{100 * COST_TOLERANCE:g} % and its speed within {SPEED_TOLERANCE:g} m/s "
                f"(all seeds: costs {self.cost_spread_pct:.1f} % and speeds "
                f"{self.speed_spread_m_per_s:.3f} m/s apart): {verdict} (settling needs "
                f"{MIN_SEEDS} agreeing seeds).")


def seed_agreement(costs: Sequence[float], speeds: Sequence[float]) -> SeedAgreement:
    """Compare the seeds' best costs [–] and mean speeds [m/s], evaluated on common copies.
    A seed whose cost is not finite never agrees."""
    if len(costs) != len(speeds) or not costs:
        raise ValueError("one cost and one speed per seed, at least one seed")
    finite = [i for i, c in enumerate(costs) if math.isfinite(c)]
    if not finite:
        return SeedAgreement(len(costs), (False,) * len(costs), math.nan, math.nan, False)
    best = min(finite, key=lambda i: costs[i])
    agreeing = tuple(
        i in finite and costs[i] <= costs[best] * (1 + COST_TOLERANCE)
        and abs(speeds[i] - speeds[best]) <= SPEED_TOLERANCE
        for i in range(len(costs)))
    fc = [costs[i] for i in finite]
    fs = [speeds[i] for i in finite]
    return SeedAgreement(
        seeds=len(costs),
        agreeing=agreeing,
        cost_spread_pct=100 * (max(fc) - min(fc)) / min(fc) if min(fc) > 0 else math.nan,
        speed_spread_m_per_s=max(fs) - min(fs),
        settled=sum(agreeing) >= MIN_SEEDS,
    )
