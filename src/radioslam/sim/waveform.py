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

from dataclasses import dataclass

import numpy as np
import scipy.fft as sfft

from radioslam.nr.numerology import Numerology
from radioslam.nr.ofdm import symbol_starts
from radioslam.nr.qam import qam16_modulate
from radioslam.sim.channel import unit_roots
from radioslam.sim.workers import worker_pool

SYNTHESIS_BLOCK_BEAMS = 24  # beams per task: their buffers stay in cache


@dataclass(frozen=True)
class BurstSymbols:
    """What each beam sends, (B, 1 + R, n_sc) as a grid: its PSS symbol, then the 16-QAM of its bits
    (B, R, 4·n_sc). Indexing with beam rows maps just those beams, so the synthesis builds each block's
    symbols where it uses them and the whole grid never exists at once."""

    pss: np.ndarray  # (n_sc,)
    bits: np.ndarray

    @property
    def shape(self) -> tuple[int, int, int]:
        return self.bits.shape[0], 1 + self.bits.shape[1], len(self.pss)

    def __getitem__(self, rows: np.ndarray) -> np.ndarray:
        grid = np.empty((len(rows), *self.shape[1:]), dtype=np.complex64)
        grid[:, 0] = self.pss
        qam16_modulate(self.bits[rows], out=grid[:, 1:])
        return grid


def synthesize_windows(tx_grid: np.ndarray | BurstSymbols, cp: np.ndarray, cumulative: np.ndarray, d_min: int,
                       numerology: Numerology, window_length: int) -> np.ndarray:
    """Received windows (B, W) complex64 for TX grids (B, L, n_sc) (an array or :class:`BurstSymbols`)
    with CP lengths (B, L).

    ``cumulative`` (M+1, B, n_sc) and ``d_min`` come from
    :func:`radioslam.sim.channel.binned_channel_response`; window sample 0 is the
    start of the beam's transmitted burst. Beams are processed in blocks (of up to
    SYNTHESIS_BLOCK_BEAMS sharing a CP pattern) on two threads, each writing its own rows;
    everything else is vectorized, in single precision.
    """
    n = numerology.fft_size
    m_count = cumulative.shape[0] - 1
    d_max = d_min + m_count
    if d_max + (cp + n).sum(axis=1).max() > window_length:
        raise ValueError(f"window of {window_length} samples is shorter than delay + burst")
    p = numerology.subcarrier_indices()
    out = np.empty((tx_grid.shape[0], window_length), dtype=np.complex64)
    out[:, :d_max] = 0.0  # before the first gate; each beam's burst and what follows are written below
    grid = tx_grid if isinstance(tx_grid, BurstSymbols) else np.asarray(tx_grid, dtype=np.complex64)
    cumulative = np.asarray(cumulative, dtype=np.complex64)
    offsets = d_min + np.arange(m_count)
    patterns, which = np.unique(cp, axis=0, return_inverse=True)
    members = [np.flatnonzero(which.ravel() == g) for g in range(len(patterns))]
    tasks = [(g, block) for g, rows in enumerate(members)
             for block in np.array_split(rows, -(-len(rows) // SYNTHESIS_BLOCK_BEAMS))]

    def synthesize(k: int) -> None:  # one block of beams sharing a CP pattern
        pattern, rows = patterns[tasks[k][0]], tasks[k][1]
        sent = grid[rows]
        prefix = CyclicPrefixes(pattern, n)
        # the full H seen from d_max late, times the usual prefix's e^{−j2πp·cp/N}
        settled = cumulative[-1, rows] * unit_roots(d_max - prefix.usual, p, n)
        _write_settled(out, rows, sent, settled, prefix, d_max, numerology)
        out[rows, d_max + prefix.boundaries[-1]:] = 0.0  # after the burst
        if m_count:  # the partial channels C_m·e^{j2πpm/N} at each boundary offset m
            partial = cumulative[:m_count, rows].transpose(1, 0, 2) * unit_roots(offsets, p, n)
            _add_boundaries(out, rows, sent, partial, prefix, offsets, p)

    list(worker_pool().map(synthesize, range(len(tasks))))  # blocks write disjoint rows: same result
    return out


class CyclicPrefixes:
    """One CP pattern (L,): where its symbols start, and e^{−j2πp·cp_l/N} as the usual (most common)
    prefix's factor, applied with another factor at once, times a fix on the few symbols that differ."""

    def __init__(self, pattern: np.ndarray, fft_size: int):
        values, counts = np.unique(pattern, return_counts=True)
        self.pattern, self.n, self.usual = pattern, fft_size, int(values[np.argmax(counts)])
        self.starts = symbol_starts(pattern, fft_size)  # (L,)
        self.boundaries = np.append(self.starts, (pattern + fft_size).sum())  # and the burst's end
        self.unusual = np.flatnonzero(pattern != self.usual)

    def fix_unusual(self, symbols: np.ndarray, frequencies: np.ndarray) -> None:
        """Symbols (R, L, F) at ``frequencies`` (F,) that carry the usual factor: give the others theirs."""
        for symbol in self.unusual:  # one or two per pattern
            symbols[:, symbol] *= unit_roots(self.usual - self.pattern[symbol], frequencies, self.n)


def _write_settled(out, rows, sent, settled, prefix: CyclicPrefixes, d_max: int, numerology: Numerology) -> None:
    """Where every path is inside the same symbol: symbol l through the full channel H, periodically
    extended over its N + cp_l samples from its (latest) gate on. One IFFT per symbol."""
    n, negative, n_sc = numerology.fft_size, numerology.n_subcarriers // 2, numerology.n_subcarriers
    spectrum = np.empty((*sent.shape[:2], n), dtype=np.complex64)  # DC-centred FFT bins
    spectrum[..., n_sc - negative:n - negative] = 0.0  # the guard band
    np.multiply(sent[..., :negative], settled[:, None, :negative], out=spectrum[..., n - negative:])
    np.multiply(sent[..., negative:], settled[:, None, negative:], out=spectrum[..., :n_sc - negative])
    prefix.fix_unusual(spectrum, np.arange(n))  # bin k is subcarrier k mod N: the same root of unity
    periodic = sfft.ifft(spectrum, axis=-1, norm="ortho", overwrite_x=True)
    for symbol, (start, cp) in enumerate(zip(prefix.starts + d_max, prefix.pattern)):  # 13 symbols, sliced
        out[rows, start:start + n] = periodic[:, symbol]
        out[rows, start + n:start + n + cp] = periodic[:, symbol, :cp]


def _add_boundaries(out, rows, sent, partial, prefix: CyclicPrefixes, offsets, p: np.ndarray) -> None:
    """In the d_max − d_min samples after each symbol boundary only some paths have moved on:
    add Σ_p C_m(p)·e^{j2πpm/N}·(a_{l,p}e^{−j2πp·cp_l/N} − a_{l−1,p}) (symbols −1 and L silent),
    one (M × n_sc)·(n_sc × L+1) matrix product per beam."""
    count, n = sent.shape[1], prefix.n
    steps = np.empty((len(rows), count + 1, sent.shape[2]), dtype=np.complex64)  # a_l·e^{…} − a_{l−1}
    np.multiply(sent, unit_roots(-prefix.usual, p, n), out=steps[:, :count])
    prefix.fix_unusual(steps, p)
    steps[:, count] = 0.0
    steps[:, 1:] -= sent
    correction = partial @ steps.transpose(0, 2, 1)
    correction /= np.float32(np.sqrt(n))
    at = (prefix.boundaries[None, :] + offsets[:, None]).ravel()  # (M·(L+1),) matching correction's (M, L+1)
    out[rows[:, None], at[None, :]] += correction.reshape(len(rows), -1)
