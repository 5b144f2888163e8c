"""Fractional-IFFT bisection of range-profile peaks (T2), paper §III-A.

"Initially, we perform an N_c IFFT on H to obtain discrete PDP samples, extracting
the K̂ largest peaks. For each peak, we identify the adjacent point with the next
highest magnitude and compute a fractional IFFT at the midpoint between the peak
and this adjacent point. If the magnitude at this midpoint surpasses that of the
current peak, it replaces the peak; otherwise, it replaces the adjacent point."

So each step keeps the larger pair of {peak, midpoint, neighbour} and halves the
bracket; after n steps the peak is known to 2^−n samples (c/(2f_s)·2^−n in range).
One step costs one evaluation of the profile at a fractional lag per peak (the midpoint on
the side of the higher neighbour): the fractional IFFT, by Kaiser–Bessel interpolation
(:class:`~radioslam.nr.nufft.LagSums`, equal to the n_sc-term sum to 1e-13).
Only the peaks marked active are refined (the others keep their integer lag), so
peaks that do not exist, or cannot become the beam's strongest, cost nothing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from radioslam.sensing.profile import RangeSpectrum


@dataclass(frozen=True)
class RefinedPeaks:
    """Refined lags (B, K) in samples after the window offset, their complex amplitudes F(lag)."""

    lag: np.ndarray
    amplitude: np.ndarray
    dft_evaluations: int  # n_sc-term DFT evaluations spent (the IFFT itself not included)


def iterations_for(precision_samples: float, max_iterations: int) -> int:
    """Bisection steps until the bracket is at most ``precision_samples`` wide."""
    return int(min(max_iterations, max(0, np.ceil(np.log2(1.0 / precision_samples)))))


def bisect_peaks(spec: RangeSpectrum, peaks: np.ndarray, values: np.ndarray, iterations: int,
                 active: np.ndarray | None = None) -> RefinedPeaks:
    """Refine integer peak lags (B, K), given F at lags peak − 1, peak, peak + 1 (B, K, 3).

    Vectorized over the active (beam, peak) pairs (B, K) (default: all); ``iterations``
    halvings of the one-sample bracket.
    """
    lag, value = peaks.astype(np.float64), values[..., 1].copy()
    beams, slots = np.nonzero(np.ones(peaks.shape, bool) if active is None else active)
    if len(beams) == 0 or iterations == 0:
        return RefinedPeaks(lag, value, 0)
    sub = spec.rows(beams)  # one row per active peak
    v = values[beams, slots]
    side = np.where(np.abs(v[:, 2]) >= np.abs(v[:, 0]), 1.0, -1.0)  # towards the higher neighbour
    at, best = lag[beams, slots], v[:, 1]
    width = 1.0
    for _ in range(iterations):  # log2(1/precision) steps, each vectorized over the active peaks
        half = width / 2.0
        mid_value = sub.at((at + side * half)[:, None])[:, 0]
        # keep the larger pair: the midpoint becomes the peak (the old peak its neighbour),
        # or the midpoint becomes the neighbour (the peak stays)
        move = np.abs(mid_value) > np.abs(best)
        at = np.where(move, at + side * half, at)
        best = np.where(move, mid_value, best)
        side = np.where(move, -side, side)
        width = half
    lag[beams, slots], value[beams, slots] = at, best
    return RefinedPeaks(lag, value, iterations * len(beams))


def neighbour_values(profile: np.ndarray, peaks: np.ndarray) -> np.ndarray:
    """F at peak − 1, peak, peak + 1 (B, K, 3) read from an integer-lag profile (B, N)."""
    n = profile.shape[1]
    idx = (peaks[..., None] + np.arange(-1, 2)) % n
    return np.take_along_axis(profile[:, None, :], idx, axis=-1)
