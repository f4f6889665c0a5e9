"""Zero-lag Butterworth low-pass filtering that respects gaps (fill, filter, restore).

Marker trajectories have gaps (NaN). As in kineticstoolkit, short interior gaps are filled
(cubic spline through the valid samples), the signal is filtered forward and backward, and the
gaps are restored to NaN afterwards so that filtering never invents data. An interior gap longer
than ``max_gap`` [s] is an error (it cannot be filled reliably); leading and trailing gaps are
left as they are and only the valid span is filtered.

``order`` is the order of the designed filter; forward-backward filtering doubles it and
squares the magnitude response (−6 dB at the cut-off). Seed 002 filters forces at 75 Hz and
markers at 20 Hz with a 4th-order Butterworth.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from bladelab.errors import DataError

__all__ = ["fill_gaps", "lowpass"]


def fill_gaps(
    data: np.ndarray,
    *,
    rate: float,
    max_gap: float,
    where: str = "signal",
    file: str | Path | None = None,
    first_frame: int = 0,
) -> tuple[np.ndarray, np.ndarray]:
    """Fill interior NaN gaps of at most ``max_gap`` seconds by cubic-spline interpolation.

    Parameters
    ----------
    data
        Samples, shape (n,) or (n, k) (columns filled independently; a row is a gap when any of
        its values is NaN).
    rate
        Sampling rate [Hz].
    max_gap
        Longest interior gap [s] that may be filled.
    where, file
        Names used in error messages (channel/marker, file).
    first_frame
        Frame number of ``data[0]`` in the trial (for error messages).

    Returns
    -------
    filled, gap_mask
        The filled copy (leading/trailing gaps stay NaN) and a boolean (n,) mask of the rows that
        were gaps in the input.

    Raises
    ------
    DataError
        An interior gap is longer than ``max_gap``; the message gives its frames and times.
    """
    arr = np.array(data, dtype=float, copy=True)
    one_d = arr.ndim == 1
    if one_d:
        arr = arr[:, None]
    gap = ~np.all(np.isfinite(arr), axis=1)
    valid = np.flatnonzero(~gap)
    if valid.size == 0 or not gap.any():
        return (arr[:, 0] if one_d else arr), gap
    first, last = valid[0], valid[-1]
    interior = gap.copy()
    interior[:first] = False
    interior[last + 1 :] = False
    if interior.any():
        edges = np.flatnonzero(np.diff(np.concatenate([[0], interior.astype(int), [0]])))
        starts, ends = edges[::2], edges[1::2]
        lengths = ends - starts
        longest = int(np.argmax(lengths))
        if lengths[longest] / rate > max_gap + 1e-12:
            s, e = int(starts[longest]) + first_frame, int(ends[longest]) + first_frame
            raise DataError(
                f"gap of {lengths[longest]} frames ({lengths[longest] / rate:.3f} s) at frames "
                f"{s}–{e - 1} (t = {s / rate:.3f}–{(e - 1) / rate:.3f} s) is longer than the fill "
                f"limit {max_gap:.3f} s",
                file=file, where=where,
                hint="raise the fill limit (max_gap) or repair the trajectory in the capture software",
            )
        if valid.size >= 2:
            from scipy import interpolate  # here, not at the top: `bladelab trial info` stays quick

            interp = interpolate.CubicSpline(valid, arr[valid], axis=0)
            idx = np.flatnonzero(interior)
            arr[idx] = interp(idx)
        else:  # pragma: no cover - a single valid sample has no interior gap
            pass
    return (arr[:, 0] if one_d else arr), gap


def lowpass(
    data: np.ndarray,
    rate: float,
    cutoff: float,
    *,
    order: int = 4,
    max_gap: float = 0.1,
    where: str = "signal",
    file: str | Path | None = None,
    first_frame: int = 0,
) -> np.ndarray:
    """Zero-lag Butterworth low-pass along axis 0, gap-aware (fill, filter, restore).

    Parameters
    ----------
    data
        Samples, shape (n,) or (n, k); NaN marks gaps.
    rate
        Sampling rate [Hz].
    cutoff
        Cut-off frequency [Hz], below the Nyquist frequency ``rate / 2``.
    order
        Order of the designed filter (doubled by forward-backward filtering).
    max_gap
        Longest interior gap [s] that is filled before filtering.
    where, file, first_frame
        Names and frame offset used in error messages.

    Returns
    -------
    numpy.ndarray
        Filtered copy, same shape; gaps are NaN again.

    Raises
    ------
    DataError
        The cut-off is not below Nyquist, or a gap is longer than ``max_gap``.
    """
    if not 0.0 < cutoff < rate / 2.0:
        raise DataError(
            f"cut-off {cutoff:g} Hz must be between 0 and the Nyquist frequency {rate / 2.0:g} Hz",
            file=file, where=where, hint="lower the cut-off",
        )
    filled, gap = fill_gaps(
        data, rate=rate, max_gap=max_gap, where=where, file=file, first_frame=first_frame
    )
    arr = filled[:, None] if filled.ndim == 1 else filled
    out = np.full_like(arr, np.nan)
    finite = np.all(np.isfinite(arr), axis=1)
    idx = np.flatnonzero(finite)
    if idx.size:
        from scipy import signal  # here, not at the top: `bladelab trial info` stays quick

        a, b = idx[0], idx[-1] + 1  # the valid span (interior gaps already filled)
        sos = signal.butter(order, cutoff, btype="low", fs=rate, output="sos")
        span = arr[a:b]
        n = span.shape[0]
        padlen = min(3 * (2 * len(sos) + 1), n - 1)
        if n >= 2 and padlen >= 0:
            out[a:b] = signal.sosfiltfilt(sos, span, axis=0, padlen=padlen)
        else:
            out[a:b] = span
    out[gap] = np.nan
    return out[:, 0] if filled.ndim == 1 else out
