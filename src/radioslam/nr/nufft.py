"""Band-limited sums at fractional lags by Kaiser–Bessel interpolation (a type-2 non-uniform FFT).

F(t) = Σ_p X(p)·e^{+j2πpt/N} over contiguous subcarriers p, and its lag derivatives, at any
lags t, for many rows at once (each row its own lags). The classic gridding scheme
(Dutt & Rokhlin 1993; Beatty, Nishimura & Pauly, "Rapid gridding reconstruction with a
minimal oversampling ratio", IEEE TMI 24(6), 2005; FINUFFT's interface, Barnett et al. 2019):

1. Deconvolve and transform once per spectrum: with q = p − p_c (p_c the band's centre),
   G(n) = Σ_q X(p_c + q)/φ̂(q)·e^{j2πqn/n_f}, one inverse FFT of n_f = u·N ≥ 1.25·n_sc points.
2. Interpolate per lag: with s = u·t, Σ_n G(n)·φ(s − n) over the W grid points within the
   kernel's support equals e^{−j2πp_c t/N}·F(t), up to the aliases φ̂(q ± n_f) of a kernel
   concentrated in the band (Poisson summation); derivatives follow from φ′ and φ″.

φ is the Kaiser–Bessel kernel I0(β√(1 − (2x/W)²)), β = π√(W²(1 − 1/(2σ))² − 0.8) for the
oversampling σ = n_f/n_sc (Beatty et al. eq. 5). It is an analytic function of x² inside
its support, so φ′ and φ″ stay finite at its edge, where the exponential-of-semicircle
kernel's do not. W = 20 at σ ≥ 1.25 leaves ≤ 1e-12 of Σ|X| (≤ 4e-11 for the second
derivative): one evaluation costs W multiply-adds instead of n_sc (792). The kernel and
its derivatives at the W taps come from a table of polynomials in the lag's fraction
(FINUFFT's "Horner" evaluation), one small product per call.

Why not FINUFFT itself: its batched transforms share one set of points across rows,
and here every row (beam) has its own lags; a plan per row costs more than the sums.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import scipy.fft as sfft
from numpy.lib.stride_tricks import sliding_window_view
from numpy.polynomial import chebyshev
from scipy.special import i0e

from radioslam.nr.ofdm import contiguous_subcarriers, place_in_bins

KERNEL_WIDTH = 20  # grid points per lag
MIN_OVERSAMPLING = 1.25  # the fine grid n_f is N·2^k with at least this many points per subcarrier
QUADRATURE_NODES = 256  # Gauss–Legendre nodes for φ̂ (converged to 1e-15 for W = 20)
POLYNOMIAL_DEGREE = 12  # of the kernel's piecewise-polynomial table


def kaiser_bessel(x: np.ndarray, width: float, beta: float) -> np.ndarray:
    """φ(x) = I0(β√(1 − (2x/W)²)) inside |x| < W/2, 0 outside, divided by e^β (a scale every use cancels)."""
    z = 2.0 * x / width
    u = beta * np.sqrt(np.clip(1.0 - z * z, 0.0, None))
    return np.where(np.abs(z) < 1.0, i0e(u) * np.exp(u - beta), 0.0)


@lru_cache(maxsize=16)
def kernel_table(width: int, beta: float, degree: int) -> np.ndarray:
    """Chebyshev coefficients (degree + 1, 3, W) in y = 2f − 1 of φ(f − o), dφ/df and d²φ/df² for each
    tap o = 1 − W/2 … W/2 and f ∈ [0, 1) (FINUFFT's piecewise-polynomial kernel evaluation): the
    interpolant at degree + 1 Chebyshev nodes."""
    y = np.cos(np.pi * (np.arange(degree + 1) + 0.5) / (degree + 1))
    taps = np.arange(1 - width // 2, 1 + width // 2)
    values = kaiser_bessel((y[None, :] + 1.0) / 2.0 - taps[:, None], width, beta)  # (W, degree + 1)
    value = np.stack([chebyshev.chebfit(y, v, degree) for v in values])  # (W, degree + 1)
    table = np.zeros((degree + 1, 3, width))
    for order in range(3):  # d/df = 2·d/dy
        derivative = chebyshev.chebder(value, order, scl=2.0, axis=1)
        table[:derivative.shape[1], order] = derivative.T
    return table


@lru_cache(maxsize=16)
def _deconvolution(q0: int, count: int, grid: int, width: int, beta: float) -> np.ndarray:
    """1/φ̂(q) for q = q0 … q0 + count − 1, φ̂(q) = ∫ φ(x)·e^{−j2πqx/n_f} dx (φ is even: a cosine)."""
    nodes, weights = np.polynomial.legendre.leggauss(QUADRATURE_NODES)
    x, w = nodes * width / 2.0, weights * width / 2.0
    q = q0 + np.arange(count)
    transform = np.cos(2.0 * np.pi * np.outer(q, x) / grid) @ (kaiser_bessel(x, width, beta) * w)
    return 1.0 / transform


class LagSums:
    """Σ_p X(p)·e^{+j2πp·t/N} of spectra X (B, n_sc) and its lag derivatives at fractional lags."""

    def __init__(self, values: np.ndarray, subcarriers: np.ndarray, period: int):
        p0, n = contiguous_subcarriers(subcarriers)
        self.period, self.centre = int(period), p0 + n // 2
        self.upsample = 1
        while self.upsample * self.period < MIN_OVERSAMPLING * n:
            self.upsample *= 2
        self.size = self.upsample * self.period  # n_f
        sigma = self.size / n
        self.width = KERNEL_WIDTH
        self.beta = float(np.pi * np.sqrt(self.width**2 * (1.0 - 0.5 / sigma) ** 2 - 0.8))
        q0 = p0 - self.centre
        weighted = values * _deconvolution(q0, n, self.size, self.width, self.beta)
        bins = place_in_bins(weighted, q0, self.size)
        grid = sfft.ifft(bins, axis=1, norm="forward", workers=-1, overwrite_x=True)  # G (B, n_f)
        # G with W points of its other end either side (grid point n at column n + W): a tap's column
        # needs no wrapping, only its base
        if self.size >= self.width:  # by slices (a tenth of the gather's time)
            self.padded = np.concatenate([grid[:, -self.width:], grid, grid[:, :self.width]], axis=1)
        else:  # a grid narrower than the kernel wraps more than once
            self.padded = grid[:, np.arange(-self.width, self.size + self.width) % self.size]
        self.table = kernel_table(self.width, self.beta, POLYNOMIAL_DEGREE)
        self.taps = np.arange(1 - self.width // 2, 1 + self.width // 2)
        self.tap_columns = self.taps + self.width  # of the taps of grid point 0 in ``padded``

    def __call__(self, lags: np.ndarray, rows: np.ndarray | None = None, order: int = 0) -> np.ndarray:
        """F and its lag derivatives up to ``order`` (≤ 2) at lags (B, K), or of ``rows`` (R,) at lags
        (R, K): (order + 1, R, K)."""
        lags = np.asarray(lags, dtype=np.float64)
        s = lags * self.upsample
        base = np.floor(s)
        columns = (base.astype(np.int64) % self.size)[..., None] + self.tap_columns  # (R, K, W)
        h = np.einsum("rkw,rkdw->drk", self._at_columns(columns, rows), self._weights(s - base, order))
        return self._from_centre(h, lags, order)

    def run(self, start: np.ndarray, count: int, rows: np.ndarray | None = None) -> np.ndarray:
        """F at the lags start, start + 1, …, start + count − 1 of each row (start (R,)): (R, count). Lags an
        integer apart share their fraction, so the kernel's weights are computed once per row, and their
        taps are windows of one contiguous stretch of the grid."""
        start = np.asarray(start, dtype=np.float64)
        s = start * self.upsample
        base = np.floor(s)
        span = (count - 1) * self.upsample + self.width
        stretch = (base.astype(np.int64)[:, None] + (self.taps[0] + np.arange(span))) % self.size + self.width
        g = sliding_window_view(self._at_columns(stretch, rows), self.width, axis=1)[:, ::self.upsample]  # (R, C, W)
        h = (g @ self._weights(s - base, 0)[:, 0, :, None])[..., 0]
        return self._from_centre(h[None], start[:, None] + np.arange(count), 0)[0]

    def _weights(self, fraction: np.ndarray, order: int) -> np.ndarray:
        """The kernel and its derivatives up to ``order`` at the W taps of grid fractions (...) in [0, 1):
        (..., order + 1, W), from the Chebyshev table."""
        angle = np.arccos(2.0 * fraction - 1.0)  # T_k(y) = cos(k·arccos y): the basis (..., D + 1)
        basis = np.cos(angle[..., None] * np.arange(len(self.table)))
        return (basis @ self.table[:, :order + 1].reshape(len(self.table), -1)).reshape(
            *fraction.shape, order + 1, self.width)

    def _at_columns(self, columns: np.ndarray, rows: np.ndarray | None) -> np.ndarray:
        """G at the ``columns`` (R, ...) of ``padded`` of each row."""
        index = np.arange(len(self.padded)) if rows is None else np.asarray(rows)
        flat = index.reshape(-1, *(1,) * (columns.ndim - 1)) * self.padded.shape[1] + columns
        return np.take(self.padded.reshape(-1), flat)  # one flat gather: half the time of a two-axis index

    def _from_centre(self, h: np.ndarray, lags: np.ndarray, order: int) -> np.ndarray:
        """F and its derivatives (order + 1, R, K) from H, the sums about the band's centre (per unit of
        the fine grid)."""
        if self.upsample != 1:
            h = h * (self.upsample ** np.arange(order + 1))[:, None, None]
        # F = e·H with e = e^{jω_c t}: the product rule for the band's centre
        jw = 2j * np.pi * self.centre / self.period
        if jw == 0:
            return h
        out = [h[0]]
        if order >= 1:
            out.append(h[1] + jw * h[0])
        if order >= 2:
            out.append(h[2] + 2 * jw * h[1] + jw**2 * h[0])
        return np.stack(out) * np.exp(jw * lags)[None]
