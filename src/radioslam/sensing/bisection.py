"""Fractional-IFFT bisection of range-profile peaks (T2), paper §III-A.

"Initially, we perform an N_c IFFT on H to obtain discrete PDP samples, extracting
the K̂ largest peaks. For each peak, we identify the adjacent point with the next
highest magnitude and compute a fractional IFFT at the midpoint between the peak
and this adjacent point. If the magnitude at this midpoint surpasses that of the
current peak, it replaces the peak; otherwise, it replaces the adjacent point."

So each step keeps the larger pair of {peak, midpoint, neighbour} and halves the
bracket; after n steps the peak is known to 2^−n samples (c/(2f_s)·2^−n in range).
One step costs one n_sc-term DFT evaluation per peak, with no exponentials: the
state is the spectrum rotated to the current peak, G(p) = S(p)·e^{j2πpa/N}, and a
step multiplies it by e^{±jπp·2^−n/N}, a vector shared by every beam and peak.
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


def integer_rotation(p: np.ndarray, lags: np.ndarray, fft_size: int) -> np.ndarray:
    """e^{j2πp·k/N} for integer lags (B, K) → (B, K, n_sc), from a table of N roots of unity."""
    roots = np.exp(2j * np.pi * np.arange(fft_size) / fft_size)
    return roots[(lags[..., None].astype(np.int64) * p) % fft_size]


def bisect_peaks(spec: RangeSpectrum, peaks: np.ndarray, values: np.ndarray, iterations: int) -> RefinedPeaks:
    """Refine integer peak lags (B, K), given F at lags peak − 1, peak, peak + 1 (B, K, 3).

    Vectorized over beams and peaks; ``iterations`` halvings of the one-sample bracket.
    """
    n = spec.fft_size
    power = np.abs(values) ** 2
    side = np.where(power[..., 2] >= power[..., 0], 1.0, -1.0)  # towards the higher neighbour
    lag = peaks.astype(np.float64)
    value = values[..., 1]
    # complex128: near the peak |F| changes by ~1e-6 per step, below float32 resolution
    rotated = spec.s[:, None, :].astype(np.complex128) * integer_rotation(spec.p, peaks, n)
    scale = spec.scale[:, None]
    width = 1.0
    for _ in range(iterations):  # log2(1/precision) steps, each vectorized over beams × peaks
        half = width / 2.0
        step_up = np.exp(1j * np.pi * spec.p * width / n).astype(rotated.dtype)  # e^{j2πp(half)/N}
        steps = np.stack([step_up.conj(), step_up])  # towards lower and higher lags
        sums = rotated @ steps.T  # (B, K, 2): the DFT at both candidate midpoints, one BLAS call
        up = side > 0
        mid_value = np.where(up, sums[..., 1], sums[..., 0]) / scale
        move = np.abs(mid_value) > np.abs(value)
        # keep the larger pair: the midpoint becomes the peak (the old peak its neighbour),
        # or the midpoint becomes the neighbour (the peak stays)
        lag = np.where(move, lag + side * half, lag)
        value = np.where(move, mid_value, value)
        rotated[move] *= steps[up[move].astype(np.int64)]
        side = np.where(move, -side, side)
        width = half
    return RefinedPeaks(lag, value, iterations * peaks.size)


def neighbour_values(profile: np.ndarray, peaks: np.ndarray) -> np.ndarray:
    """F at peak − 1, peak, peak + 1 (B, K, 3) read from an integer-lag profile (B, N)."""
    n = profile.shape[1]
    idx = (peaks[..., None] + np.arange(-1, 2)) % n
    return np.take_along_axis(profile[:, None, :], idx, axis=-1)
