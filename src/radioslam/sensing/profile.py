"""Range profiles: the PDP and the matched-filter output (paper §III-A, §III-B).

Both are N_c-point IFFTs of a spectrum on the active subcarriers p:

* PDP: of the channel estimate Ĥ = Z/W, F(t) = (1/n_sc) Σ_p Ĥ(p) e^{j2πpt/N};
* MF with coherent integration: of Z = Σ_q y_q x_q*, F(t) = Σ_p Z(p) e^{j2πpt/N} / Σ_p W(p).

Either is scaled so that one path b·e^{−j2πpd/N} gives F(d − offset) = b: |F|² is
the path's power in both. t is the lag in samples after the FFT window offset.
A taper (Hann) across the subcarriers trades main-lobe width for lower range
sidelobes of the band edge (the Dirichlet kernel of 792 of 1024 subcarriers).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.fft as sfft

from radioslam.nr.nufft import LagSums
from radioslam.nr.ofdm import place_in_bins, summed_phase_ramps
from radioslam.sensing.config import Taper
from radioslam.sensing.estimate import ChannelEstimate


def divide_by_real(values: np.ndarray, divisor: np.ndarray) -> None:
    """values (B, N) complex /= divisor (B,) real, in place: the real and imaginary parts each divided
    (correctly rounded; numpy's complex division, within one ulp of it, costs four times as much)."""
    values.view(values.real.dtype).reshape(len(values), -1)[...] /= divisor[:, None]


def taper_weights(kind: Taper, n_sc: int) -> np.ndarray:
    if kind is Taper.HANN:
        return np.hanning(n_sc + 2)[1:-1]
    return np.ones(n_sc)


@dataclass(frozen=True)
class RangeSpectrum:
    """A spectrum S (B, n_sc) whose IFFT is a range profile, and what scales it."""

    s: np.ndarray
    model: np.ndarray  # (B, n_sc): a path b at lag t puts b·model·e^{−j2πpt/N} into S
    p: np.ndarray  # (n_sc,) signed subcarrier indices
    fft_size: int

    @property
    def beam_count(self) -> int:
        return self.s.shape[0]

    @cached_property
    def scale(self) -> np.ndarray:
        """(B,) Σ_p model(p), so that F(t) of a lone path at lag t is its amplitude."""
        return self.model.sum(axis=1)

    def profile(self) -> np.ndarray:
        """F at the N integer lags (B, N), complex (the subcarriers are contiguous)."""
        bins = place_in_bins(self.s, int(self.p[0]), self.fft_size, np.result_type(self.s.dtype, np.complex64))
        profile = sfft.ifft(bins, axis=1, norm="forward", workers=-1, overwrite_x=True)
        divide_by_real(profile, self.scale)
        return profile

    @cached_property
    def _signal_sums(self) -> LagSums:
        return LagSums(self.s, self.p, self.fft_size)

    @cached_property
    def _kernel_sums(self) -> LagSums:
        return LagSums(self.model, self.p, self.fft_size)

    def at(self, lags: np.ndarray) -> np.ndarray:
        """F at fractional lags (B, K) (:class:`~radioslam.nr.nufft.LagSums`: 20 multiply-adds each)."""
        return self.with_derivatives(lags, order=0)[0]

    def with_derivatives(self, lags: np.ndarray, rows: np.ndarray | None = None, order: int = 2) -> np.ndarray:
        """F and its lag derivatives up to ``order`` (≤ 2) at fractional lags (B, K): (order + 1, B, K);
        with ``rows`` (R,), of those rows only, at lags (R, K)."""
        scale = self.scale if rows is None else self.scale[rows]
        return self._signal_sums(lags, rows, order) / scale[:, None]

    def kernel_with_derivatives(self, lags: np.ndarray, rows: np.ndarray | None = None, order: int = 2) -> np.ndarray:
        """:meth:`kernel` and its lag derivatives up to ``order`` at lags (B, K) (or of ``rows`` only):
        (order + 1, B, K)."""
        return self._kernel_sums(lags, rows, order)

    @cached_property
    def kernel_at_zero(self) -> np.ndarray:
        """(3, B): the kernel and its first two lag derivatives at lag 0 (Σ_p model·(jω)^k), from real
        products (the model is real, jω imaginary: a complex product would copy the model to complex)."""
        w = 2.0 * np.pi * self.p / self.fft_size
        return np.stack([self.scale, 1j * (self.model @ w), -(self.model @ w**2)]).astype(np.complex128)

    def kernel_run(self, start: np.ndarray, count: int) -> np.ndarray:
        """:meth:`kernel` at the lags start, start + 1, …, start + count − 1 (start (B,)): (B, count)."""
        return self._kernel_sums.run(start, count)

    def kernel(self, lags: np.ndarray) -> np.ndarray:
        """Σ_p model(p)·e^{j2πpt/N} at lags (B, K): the response at lag t of a path at lag 0,
        unnormalized (the Gram entries of two paths t apart)."""
        return self.kernel_with_derivatives(lags, order=0)[0]

    def path_spectrum(self, lags: np.ndarray, amplitude: np.ndarray) -> np.ndarray:
        """The spectrum (B, n_sc) that paths (B, K) of the given lags and amplitudes put in S."""
        return summed_phase_ramps(lags, amplitude, self.p, self.fft_size) * self.model

    def rows(self, mask: np.ndarray) -> "RangeSpectrum":
        """The beams selected by a boolean mask (B,) or an index array."""
        return RangeSpectrum(self.s[mask], self.model[mask], self.p, self.fft_size)

    def minus(self, spectrum: np.ndarray) -> "RangeSpectrum":
        """The residual after cancelling ``spectrum`` (successive cancellation)."""
        return RangeSpectrum(self.s - spectrum, self.model, self.p, self.fft_size)


def pdp_spectrum(est: ChannelEstimate, p: np.ndarray, fft_size: int, taper: Taper = Taper.NONE) -> RangeSpectrum:
    """PDP spectrum Ĥ = Z/W (paper §III-A)."""
    t = taper_weights(taper, len(p))
    return RangeSpectrum(est.h * t, np.broadcast_to(t, est.z.shape), p, fft_size)


def mf_spectrum(est: ChannelEstimate, p: np.ndarray, fft_size: int, taper: Taper = Taper.NONE) -> RangeSpectrum:
    """Matched filter with coherent integration, spectrum Z = Σ_q y_q x_q* (paper §III-B)."""
    t = taper_weights(taper, len(p))
    return RangeSpectrum(est.z.astype(np.complex128) * t, est.w * t, p, fft_size)


def signed_lag(lag: np.ndarray, fft_size: int) -> np.ndarray:
    """Lags wrapped to [−N/2, N/2): a path before the window offset has a negative lag."""
    return (np.asarray(lag) + fft_size // 2) % fft_size - fft_size // 2
