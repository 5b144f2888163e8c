"""Exact time-domain synthesis of the received beam window (waveform mode).

The NR baseband signal (38.211 §5.3.1) is, symbol by symbol, a gated sum of
subcarriers. A path with delay τ (τ·f_s = d − φ, d = ⌈τ·f_s⌉) therefore arrives
with each symbol's gate shifted by the integer d and the symbol's content
Σ_p a_p·e^{−j2πpΔfτ}·e^{j2πp(n − n_u)/N} — exact for any fractional delay, with no
interpolation filter. Summing paths:

* wherever every path is inside the same symbol the window equals the symbol
  OFDM-modulated through the full channel H(p), periodically extended (the
  "base", computed with one IFFT per symbol);
* in the d_max − d_min samples after each symbol boundary some paths have moved
  on: the correction there is Σ_p C_m(p)·e^{j2πpm/N}·(a_{l+1,p}e^{−j2πp·cp/N} − a_{l,p})
  with C_m the response of the paths arrived by offset m. It factorizes into one
  small matrix product per beam, (M × n_sc)·(n_sc × L+1).

Demodulating this window anywhere inside the cyclic prefix returns exactly
H(p)·a_p (times the window-timing phase): the grid mode of eq. (4).
"""

from __future__ import annotations

import numpy as np
import scipy.fft as sfft

from radioslam.nr.numerology import Numerology
from radioslam.nr.ofdm import cp_gather_index, symbol_starts, to_fft_bins


def _boundary_factors(tx_grid: np.ndarray, cp: np.ndarray, p: np.ndarray, n: int) -> np.ndarray:
    """a_{l,p}·e^{−j2πp·cp_l/N} − a_{l−1,p} for the boundaries l = 0 … L (symbols −1 and L silent)."""
    rotated = tx_grid * np.exp(-2j * np.pi * np.outer(cp, p) / n).astype(tx_grid.dtype)[None]
    d = np.zeros((tx_grid.shape[0], tx_grid.shape[1] + 1, tx_grid.shape[2]), dtype=tx_grid.dtype)
    d[:, :-1] = rotated
    d[:, 1:] -= tx_grid
    return d


def synthesize_windows(tx_grid: np.ndarray, cp: np.ndarray, cumulative: np.ndarray, d_min: int,
                       numerology: Numerology, window_length: int) -> np.ndarray:
    """Received windows (B, W) complex64 for TX grids (B, L, n_sc) with CP lengths (B, L).

    ``cumulative`` (B, M+1, n_sc) and ``d_min`` come from
    :func:`radioslam.sim.channel.binned_channel_response`; window sample 0 is the
    start of the beam's transmitted burst. Beams are processed in groups that
    share a CP pattern (a handful), everything else is vectorized.
    """
    n = numerology.fft_size
    b_count = tx_grid.shape[0]
    m_count = cumulative.shape[1] - 1
    d_max = d_min + m_count
    p = numerology.subcarrier_indices()
    burst = (cp + n).sum(axis=1)
    if d_max + burst.max() > window_length:
        raise ValueError(f"window of {window_length} samples is shorter than delay + burst")
    out = np.zeros((b_count, window_length), dtype=np.complex64)
    m = d_min + np.arange(m_count)
    f = (cumulative[:, :m_count] * np.exp(2j * np.pi * np.outer(m, p) / n)[None]).astype(np.complex64)
    tx_grid = tx_grid.astype(np.complex64)
    patterns, which = np.unique(cp, axis=0, return_inverse=True)
    for g, pattern in enumerate(patterns):  # beams sharing one CP pattern (a handful of groups)
        rows = np.flatnonzero(which.ravel() == g)
        grid = tx_grid[rows]
        # base: every path inside the same symbol → OFDM through the full channel H
        through = grid * cumulative[rows, -1][:, None, :].astype(np.complex64)
        spectrum = to_fft_bins(through, numerology, np.complex64)
        useful = sfft.ifft(spectrum, axis=-1, norm="ortho", overwrite_x=True).reshape(len(rows), -1)
        length = int(pattern.sum() + n * len(pattern))
        out[rows, d_max:d_max + length] = useful[:, cp_gather_index(pattern, n, d_max)]
        if m_count == 0:
            continue
        # corrections after each symbol boundary, where only some paths have moved on
        corr = (f[rows] @ _boundary_factors(grid, pattern, p, n).transpose(0, 2, 1)) / np.float32(np.sqrt(n))
        starts = np.append(symbol_starts(pattern, n), length)
        pos = (starts[None, :] + m[:, None]).ravel()  # (M·(L+1),) matching corr's (M, L+1)
        out[rows[:, None], pos[None, :]] += corr.reshape(len(rows), -1)
    return out
