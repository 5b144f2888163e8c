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

from radioslam.nr.ofdm import BlockedSpectrum, phase_ramp
from radioslam.sensing.config import Taper
from radioslam.sensing.estimate import ChannelEstimate


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

    @cached_property
    def scale(self) -> np.ndarray:
        """(B,) Σ_p model(p), so that F(t) of a lone path at lag t is its amplitude."""
        return self.model.sum(axis=1)

    def profile(self) -> np.ndarray:
        """F at the N integer lags (B, N), complex."""
        n = self.fft_size
        bins = np.zeros((self.s.shape[0], n), dtype=np.result_type(self.s.dtype, np.complex64))
        bins[:, self.p % n] = self.s
        return sfft.ifft(bins, axis=1, norm="forward", workers=-1) / self.scale[:, None]

    @cached_property
    def _s_sum(self) -> BlockedSpectrum:
        return BlockedSpectrum(self.s, self.p, self.fft_size)

    @cached_property
    def _model_sum(self) -> BlockedSpectrum:
        return BlockedSpectrum(self.model, self.p, self.fft_size)

    def at(self, lags: np.ndarray) -> np.ndarray:
        """F at fractional lags (B, K): one n_sc-term DFT evaluation per entry."""
        return self._s_sum(lags) / self.scale[:, None]

    @cached_property
    def _derivative_sums(self) -> BlockedSpectrum:
        """S, S·jω and S·(jω)² stacked (3B, n_sc), ω = 2πp/N: F and its first two lag derivatives."""
        jw = 2j * np.pi * self.p / self.fft_size
        return BlockedSpectrum(np.concatenate([self.s, self.s * jw, self.s * jw**2]), self.p, self.fft_size)

    def at_via_derivatives(self, lags: np.ndarray) -> np.ndarray:
        """:meth:`at`, through the evaluator of :meth:`with_derivatives` (its F rows): no second
        evaluator set up where that one is already built."""
        return self._derivative_sums(lags, slice(0, self.s.shape[0])) / self.scale[:, None]

    def with_derivatives(self, lags: np.ndarray, rows: np.ndarray | None = None) -> np.ndarray:
        """F, dF/dt and d²F/dt² at fractional lags (B, K): (3, B, K), in one blocked evaluation; with
        ``rows`` (R,), of those rows only, at lags (R, K): (3, R, K)."""
        b = self.s.shape[0]
        if rows is None:  # every row: the stacked blocks as they are, no gather
            values = self._derivative_sums(np.tile(lags, (3, 1))) / np.tile(self.scale, 3)[:, None]
            return values.reshape(3, b, -1)
        rows = np.asarray(rows)
        stacked = np.concatenate([rows, rows + b, rows + 2 * b])  # F, F′ and F″ of each row
        values = self._derivative_sums(np.tile(lags, (3, 1)), stacked) / self.scale[stacked % b][:, None]
        return values.reshape(3, len(rows), -1)

    def kernel(self, lags: np.ndarray) -> np.ndarray:
        """Σ_p model(p)·e^{j2πpt/N} at lags (B, K): the response at lag t of a path at lag 0,
        unnormalized (the Gram entries of two paths t apart)."""
        return self._model_sum(lags)

    def path_spectrum(self, lags: np.ndarray, amplitude: np.ndarray) -> np.ndarray:
        """The spectrum (B, n_sc) that paths (B, K) of the given lags and amplitudes put in S."""
        phase = phase_ramp(lags, self.p, self.fft_size)
        return (amplitude[:, None, :] @ phase)[:, 0] * self.model

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
