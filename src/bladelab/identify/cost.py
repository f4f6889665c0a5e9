"""Identification cost: normalised RMSE of GRF and characteristic distance (seed 000 §2.3).

``nRMSE = RMSE / (max − min of the reference)`` and

    J = w_grf · nRMSE(GRF) + w_dst · nRMSE(distance)        (seed 000: w_grf = w_dst = 0.5)

GRF is the vertical component, or the vertical and horizontal components (then nRMSE(GRF) is the
mean of the two components' nRMSEs, each normalised by its own reference range). Both terms are
computed over the **contact window**: the samples where the measured vertical GRF exceeds
``contact_threshold`` [N]. Values are fractions (0.05 = 5 %); multiply by 100 for percent.

For least-squares based analyses (identifiability) :meth:`StanceCost.residuals` gives the residual
vector ``r`` whose squared norm is ``Σ_c w_c · nRMSE_c²``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from bladelab.errors import DataError, OptimizationError

GRF_CHANNELS = {"z": "grf_z", "x": "grf_x"}


def nrmse(simulated, reference, *, channel: str = "signal") -> np.ndarray | float:
    """Normalised RMSE of ``simulated`` against ``reference``: RMSE / (max − min of reference).

    Parameters
    ----------
    simulated
        Shape (n,) or (m, n) (m simulations of the same n samples).
    reference
        Shape (n,); must be finite and not constant.
    channel
        Name used in error messages.

    Returns
    -------
    float or ndarray
        Dimensionless nRMSE (a float for 1-D input, shape (m,) for 2-D input).

    Raises
    ------
    DataError
        Shapes differ, the reference has non-finite values or is constant.
    """
    ref = np.asarray(reference, dtype=float)
    sim = np.asarray(simulated, dtype=float)
    if ref.ndim != 1 or sim.shape[-1] != ref.shape[0]:
        raise DataError(
            f"simulated shape {sim.shape} does not match reference shape {ref.shape}", where=channel
        )
    if not np.all(np.isfinite(ref)):
        raise DataError("reference has missing or non-finite values", where=f"{channel} column")
    span = _range(ref, channel)
    rmse = np.sqrt(np.mean((sim - ref) ** 2, axis=-1))
    return float(rmse / span) if sim.ndim == 1 else rmse / span


def _range(ref: np.ndarray, channel: str) -> float:
    span = float(np.max(ref) - np.min(ref))
    scale = max(float(np.max(np.abs(ref))), 1e-300)
    if not span > 1e-9 * scale or span == 0.0:
        raise DataError(
            f"{channel} column is constant (range {span:.3g}); nRMSE is undefined",
            where=f"{channel} column",
            hint="check the export of this channel, or give it weight 0",
        )
    return span


def contact_window(grf_z, *, threshold: float = 20.0, channel: str = "grf_z") -> np.ndarray:
    """Boolean mask of the samples in contact: vertical GRF above ``threshold`` [N].

    Raises
    ------
    DataError
        No sample (or fewer than 3) is above the threshold: the stance has no contact.
    """
    grf = np.asarray(grf_z, dtype=float)
    mask = np.isfinite(grf) & (grf > threshold)
    if mask.sum() < 3:
        peak = float(np.nanmax(grf)) if grf.size and np.any(np.isfinite(grf)) else float("nan")
        raise DataError(
            f"the stance has no contact: peak vertical GRF {peak:.4g} N, "
            f"{int(mask.sum())} sample(s) above the {threshold:g} N contact threshold",
            where=f"{channel} column",
            hint="check that the window contains a foot contact and forces are in newtons",
        )
    return mask


@dataclasses.dataclass(frozen=True)
class CostTerms:
    """Cost of m simulated parameter sets (each array shape (m,), fractions not percent)."""

    cost: np.ndarray
    nrmse_grf: np.ndarray
    nrmse_distance: np.ndarray

    def to_dict(self) -> dict:
        """JSON-ready dictionary (lists of floats)."""
        return {k: np.asarray(v, float).tolist() for k, v in dataclasses.asdict(self).items()}


@dataclasses.dataclass(frozen=True, eq=False)
class StanceCost:
    """The identification cost of one stance: reference signals restricted to the contact window.

    Build it with :meth:`from_stance` (or :meth:`from_arrays`); evaluate simulated signals sampled
    on the stance's time base (full length n) with :meth:`evaluate` or :meth:`residuals`.

    Attributes
    ----------
    mask
        (n,) contact-window mask.
    references
        Channel name (``grf_z``, ``grf_x``, ``distance``) -> reference values on the window.
    spans
        Channel name -> reference range (max − min) on the window.
    grf_components
        ``("z",)`` or ``("z", "x")``.
    weights
        (w_grf, w_dst).
    """

    mask: np.ndarray
    references: dict[str, np.ndarray]
    spans: dict[str, float]
    grf_components: tuple[str, ...]
    weights: tuple[float, float]

    @classmethod
    def from_arrays(
        cls,
        *,
        grf_z,
        distance,
        grf_x=None,
        weights: tuple[float, float] = (0.5, 0.5),
        grf_components: Sequence[str] = ("z",),
        contact_threshold: float = 20.0,
    ) -> StanceCost:
        """Build from measured arrays: ``grf_z``, ``grf_x`` [N], ``distance`` [m], shape (n,).

        Raises
        ------
        DataError
            No contact; a used channel is missing, non-finite in the window, or constant.
        OptimizationError
            Weights negative or both zero; unknown GRF component.
        """
        comps = tuple(grf_components)
        if not comps or any(c not in GRF_CHANNELS for c in comps) or len(set(comps)) != len(comps):
            raise OptimizationError(
                f"grf_components={comps!r}", where="grf_components",
                hint="use ('z',) for vertical GRF or ('z', 'x') for vertical and horizontal",
            )
        w = tuple(float(v) for v in weights)
        if len(w) != 2 or min(w) < 0 or sum(w) <= 0 or not all(np.isfinite(w)):
            raise OptimizationError(
                f"weights={weights!r} must be two non-negative numbers, not both zero", where="weights"
            )
        mask = contact_window(grf_z, threshold=contact_threshold)
        signals = {"grf_z": grf_z, "grf_x": grf_x, "distance": distance}
        used = ([GRF_CHANNELS[c] for c in comps] if w[0] > 0 else []) + (["distance"] if w[1] > 0 else [])
        refs: dict[str, np.ndarray] = {}
        spans: dict[str, float] = {}
        for name in used:
            if signals[name] is None:
                raise DataError("channel is required by the cost but was not given", where=name)
            ref = np.asarray(signals[name], dtype=float)[mask]
            bad = int(np.sum(~np.isfinite(ref)))
            if bad:
                raise DataError(
                    f"{bad} missing or non-finite value(s) inside the contact window",
                    where=f"{name} column",
                    hint="fill the gaps, or give the distance term weight 0 if there is no tip marker",
                )
            spans[name] = _range(ref, name)
            refs[name] = ref
        return cls(mask=mask, references=refs, spans=spans, grf_components=comps, weights=w)

    @classmethod
    def from_stance(cls, stance, **options) -> StanceCost:
        """Build from a :class:`bladelab.trial.Stance` (options as :meth:`from_arrays`)."""
        return cls.from_arrays(grf_z=stance.grf_z, grf_x=stance.grf_x, distance=stance.distance,
                               **options)

    @property
    def n_samples(self) -> int:
        """Length n of the full stance arrays."""
        return int(self.mask.shape[0])

    def _window(self, name: str, values) -> np.ndarray:
        arr = np.atleast_2d(np.asarray(values, dtype=float))
        if arr.shape[-1] != self.n_samples:
            raise DataError(
                f"simulated {name} has {arr.shape[-1]} samples, the stance has {self.n_samples}",
                where=name, hint="simulate on the stance's time base",
            )
        return arr[:, self.mask]

    def _errors(self, simulated: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """Channel -> (m, n_window) errors simulated − reference."""
        out = {}
        for name, ref in self.references.items():
            if simulated.get(name) is None:
                raise DataError("simulated channel missing", where=name)
            out[name] = self._window(name, simulated[name]) - ref
        return out

    def evaluate(self, *, grf_z, distance, grf_x=None) -> CostTerms:
        """Cost of simulated signals, each (n,) or (m, n) on the stance's time base.

        Non-finite simulated values give an infinite cost for that row.
        """
        errs = self._errors({"grf_z": grf_z, "grf_x": grf_x, "distance": distance})
        m = next(iter(errs.values())).shape[0]
        per = {k: np.sqrt(np.mean(e**2, axis=1)) / self.spans[k] for k, e in errs.items()}
        grf_names = [GRF_CHANNELS[c] for c in self.grf_components]
        e_grf = (np.mean([per[k] for k in grf_names], axis=0) if grf_names[0] in per
                 else np.zeros(m))
        e_dst = per.get("distance", np.zeros(m))
        cost = self.weights[0] * e_grf + self.weights[1] * e_dst
        cost = np.where(np.isfinite(cost), cost, np.inf)
        return CostTerms(cost=cost, nrmse_grf=e_grf, nrmse_distance=e_dst)

    def residual_blocks(self) -> tuple[int, ...]:
        """Lengths of the blocks of :meth:`residuals`, one per channel in order (for
        :func:`bladelab.identify.identifiability.hac_inflation`)."""
        n = int(self.mask.sum())
        return tuple(n for _ in self.references)

    def residuals(self, *, grf_z, distance, grf_x=None) -> np.ndarray:
        """Weighted, normalised residuals, shape (m, n_res), with ‖r‖² = Σ_c w_c·nRMSE_c².

        Each channel c contributes ``sqrt(w_c / n_w) · (sim − ref) / range_c`` over the window,
        where w_c is w_grf divided among the GRF components, or w_dst.
        """
        errs = self._errors({"grf_z": grf_z, "grf_x": grf_x, "distance": distance})
        n_grf = len(self.grf_components)
        blocks = []
        for name, e in errs.items():
            w = self.weights[1] if name == "distance" else self.weights[0] / n_grf
            blocks.append(np.sqrt(w / e.shape[1]) * e / self.spans[name])
        return np.hstack(blocks)
