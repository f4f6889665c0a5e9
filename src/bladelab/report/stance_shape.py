"""The shape of a predicted stance beside the measured runner's: where the vertical force peaks,
how flexed the stance knee lands and where it is most flexed.

No criterion of measured running checks these (:mod:`bladelab.predict.collocation.
human_running`); the report puts them beside the criteria and under the ground-force figure, for
a solution near the measured trial's speed (the Fukuchi et al. 2017 runner RBDS001 at 3.5 m/s,
:func:`~bladelab.predict.collocation.guess.measured_trial_guess`). Places are in % of a stance's
nodes, angles in degrees of knee flexion (positive flexed). docs/collocation.md, "How a foot
lands", says why they matter: in the model as in people the force peaks about where the stance
knee is most flexed, and the model lands with the knee more flexed than people.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from bladelab.predict.collocation.nodes import periodic_runs
from bladelab.predict.collocation.solution import CONTACT_THRESHOLD_N

__all__ = ["KNEE_PEAK_AGREEMENT_PCT", "StanceShape", "knee_flexion_deg", "stance_knees",
           "stance_nodes", "stance_peak_places", "stance_shape"]

#: Force peak and deepest knee flexion closer than this [% of the stance] count as together.
KNEE_PEAK_AGREEMENT_PCT = 10.0


def stance_nodes(force: np.ndarray, threshold: float) -> list[np.ndarray]:
    """The node indices of each stance (run above ``threshold``) of a periodic force (n nodes
    of one period, without the repeated last one), in order, a stance across the end wrapped."""
    return [(start + np.arange(length)) % force.size
            for start, length in periodic_runs(force > threshold)]


def _place_pct(values: np.ndarray) -> float:
    """Where ``values`` (over one stance's nodes) is largest [% of the stance's nodes]."""
    return 100.0 * float(np.argmax(values)) / len(values)


def stance_peak_places(force: np.ndarray, threshold: float) -> list[float]:
    """Where each stance's force peaks [% of the stance's nodes] (:func:`stance_nodes`)."""
    return [_place_pct(force[nodes]) for nodes in stance_nodes(force, threshold)]


def stance_knees(force: np.ndarray, flexion: np.ndarray, threshold: float
                 ) -> list[tuple[float, float]]:
    """Per stance (runs of ``force`` above ``threshold``, periodic, n nodes without the repeated
    last one): the knee's flexion at its first node [deg] and where in it the knee is most
    flexed [% of the stance's nodes]; ``flexion`` (n,) [deg] of that stance's leg."""
    return [(float(flexion[nodes[0]]), _place_pct(flexion[nodes]))
            for nodes in stance_nodes(force, threshold)]


def knee_flexion_deg(q: np.ndarray, dof_names, side: str) -> np.ndarray | None:
    """The knee's flexion [deg, positive flexed] of leg ``side`` ('l' or 'r'), None without."""
    name = f"knee_angle_{side}"
    return None if name not in dof_names else -np.degrees(q[:, list(dof_names).index(name)])


def _listed(values) -> str:
    """Whole numbers, comma-separated."""
    return ", ".join(f"{v:.0f}" for v in values)


def _span(values) -> str:
    """The range of ``values`` as whole numbers ("a–b", "a" for one value, "–" for none)."""
    if not values:
        return "–"
    return f"{min(values):.0f}–{max(values):.0f}" if len(values) > 1 else f"{values[0]:.0f}"


@dataclass(frozen=True)
class StanceShape:
    """Per stance, in stance order: force peak places [% of the stance], and (landing knee
    flexion [deg], place of the deepest knee flexion [% of the stance]) pairs, of the solution
    (``peaks``, ``knees``; each labelled by its leg in ``legs``) and of the measured runner
    (``measured_peaks``, ``measured_knees``; empty where its knees are not known)."""

    legs: tuple[str, ...]
    peaks: tuple[float, ...]
    knees: tuple[tuple[float, float], ...]
    measured_peaks: tuple[float, ...]
    measured_knees: tuple[tuple[float, float], ...]

    @property
    def together(self) -> bool:
        """Whether every stance's force peaks within :data:`KNEE_PEAK_AGREEMENT_PCT` of where its
        knee is most flexed."""
        return bool(self.knees) and len(self.knees) == len(self.peaks) and all(
            abs(p - k[1]) <= KNEE_PEAK_AGREEMENT_PCT
            for p, k in zip(self.peaks, self.knees, strict=True))

    def table(self) -> pd.DataFrame:
        """One row per measure and stance: this stride's value beside the measured runner's
        range over its stances."""
        rows = [{"measure": f"vertical force peak, {leg} leg's stance", "this stride": round(p, 1),
                 "the measured runner": _span(self.measured_peaks), "unit": "% of the stance"}
                for leg, p in zip(self.legs, self.peaks, strict=True)]
        if self.knees and self.measured_knees:
            land = [k[0] for k in self.measured_knees]
            deep = [k[1] for k in self.measured_knees]
            which = ([f"{leg} leg's stance" for leg in self.legs]
                     if len(self.legs) == len(self.knees)
                     else [f"stance {i + 1}" for i in range(len(self.knees))])
            rows += [{"measure": f"knee flexion at touch-down, {w}", "this stride": round(k[0], 1),
                      "the measured runner": _span(land), "unit": "deg"}
                     for w, k in zip(which, self.knees, strict=True)]
            rows += [{"measure": f"deepest stance knee flexion, {w}",
                      "this stride": round(k[1], 1), "the measured runner": _span(deep),
                      "unit": "% of the stance"}
                     for w, k in zip(which, self.knees, strict=True)]
        return pd.DataFrame(rows)

    def caption_text(self) -> str:
        """The shape in words, for the ground-force figure's caption."""
        text = (" Each stance's vertical force peaks at "
                + _listed(self.peaks) + " % of its nodes here, the measured "
                "runner's at " + _listed(self.measured_peaks)
                + " % (no criterion checks it).")
        if self.knees and self.measured_knees:
            text += (" The stance knee lands at " + _listed(k[0] for k in self.knees)
                     + "° of flexion and is most flexed at "
                     + _listed(k[1] for k in self.knees)
                     + " % of the stance here, the measured runner's lands at "
                     + _listed(k[0] for k in self.measured_knees)
                     + "° and is most flexed at "
                     + _listed(k[1] for k in self.measured_knees) + " %")
            text += (": here as in the measured runner the force peaks about where the knee is "
                     "most flexed, so a landing with the knee more flexed brings the peak earlier."
                     if self.together else ".")
        return text + " (docs/collocation.md, 'How a foot lands'.)"

    def summary_text(self) -> str:
        """One sentence for the report's first section: the shape beside the measured
        runner's, said to be outside no criterion."""
        text = (" Beside the criteria, the shape of a stance (no criterion checks it; the "
                "measured runner at 3.5 m/s): the vertical force peaks at "
                + _listed(self.peaks) + " % of the stance (the measured "
                f"runner's {_span(self.measured_peaks)} %)")
        if self.knees and self.measured_knees:
            text += (" and the stance knee lands "
                     + _listed(k[0] for k in self.knees) + "° flexed (the measured "
                     f"runner's {_span([k[0] for k in self.measured_knees])}°)")
        return text + " (table below; docs/collocation.md, 'How a foot lands')."


def stance_shape(sol, trial) -> StanceShape | None:
    """The stance shape of collocation solution ``sol`` beside ``trial`` (the measured runner's
    mean stride on the solution's model, a StrideGuess with its vertical force), or None where
    there is no measured force or no stance."""
    if trial is None or trial.vertical_grf_bw is None:
        return None
    threshold = CONTACT_THRESHOLD_N / sol.body_weight_N
    fz = sol.leg_vertical_force()[:-1] / sol.body_weight_N
    total = np.asarray(trial.vertical_grf_bw)[:-1]
    legs, peaks = [], []
    for j, name in enumerate(sol.leg_names):
        places = stance_peak_places(fz[:, j], threshold)
        legs += [name] * len(places)
        peaks += places
    measured = stance_peak_places(total, threshold)
    if not peaks or not measured:
        return None
    q = np.asarray(sol.nlp.q)[:-1]
    knees = [k for j, side in enumerate("lr")
             if (flex := knee_flexion_deg(q, sol.dof_names, side)) is not None
             for k in stance_knees(fz[:, j], flex, threshold)]
    trial_legs = [knee_flexion_deg(np.asarray(trial.q)[:-1], trial.dof_names or sol.dof_names,
                                   side) for side in "lr"]
    theirs = []
    if knees and all(leg is not None for leg in trial_legs):
        # the stance leg of each measured stance (total force): the one whose knee is the
        # straighter over it (the other swings)
        for nodes in stance_nodes(total, threshold):
            leg = trial_legs[int(np.argmin([flex[nodes].mean() for flex in trial_legs]))]
            theirs.append((float(leg[nodes[0]]), _place_pct(leg[nodes])))
    return StanceShape(tuple(legs), tuple(peaks), tuple(knees), tuple(measured),
                       tuple(theirs) if knees else ())
