"""CP-OFDM modulation and demodulation (3GPP TS 38.211 §5.3.1), vectorized.

Orthonormal FFTs: unit-energy resource elements give unit-power samples over the
FFT size, and white time-domain noise of variance σ² is white with variance σ² on
every resource element. The phase reference of each symbol is the start of its
useful part (after its cyclic prefix), as in 38.211.
"""

from __future__ import annotations

import numpy as np
import scipy.fft as sfft
from numpy.lib.stride_tricks import sliding_window_view

from radioslam.nr.numerology import Numerology


def cp_gather_index(cp_lengths: np.ndarray, fft_size: int, shift: int = 0) -> np.ndarray:
    """Index into concatenated useful parts (L·N) that inserts each symbol's CP.

    Output sample j of symbol l is useful sample (j + shift − cp_l) mod N; a shift
    s gives the periodic content of symbols whose gates arrive s samples late.
    """
    cp = np.asarray(cp_lengths, dtype=np.int64)
    lengths = cp + fft_size
    starts = np.concatenate([[0], np.cumsum(lengths)[:-1]])
    symbol = np.repeat(np.arange(len(cp)), lengths)
    j = np.arange(lengths.sum()) - starts[symbol]
    return symbol * fft_size + (j + shift - cp[symbol]) % fft_size


def symbol_starts(cp_lengths: np.ndarray, fft_size: int) -> np.ndarray:
    """Sample index where each symbol (its CP) starts, for symbols sent back to back.

    Works along the last axis, so (B, L) CP lengths give (B, L) starts.
    """
    lengths = np.asarray(cp_lengths, dtype=np.int64) + fft_size
    return np.cumsum(lengths, axis=-1) - lengths


def _contiguous(subcarriers: np.ndarray) -> tuple[int, int]:
    """The first index and the count of contiguous subcarriers (the factorizations need them)."""
    p0, n = int(subcarriers[0]), len(subcarriers)
    if not np.array_equal(subcarriers, p0 + np.arange(n)):
        raise ValueError("subcarriers must be contiguous")
    return p0, n


def phase_ramp(shift: np.ndarray, subcarriers: np.ndarray, period: float) -> np.ndarray:
    """e^{−j2π·p·shift/period} for shifts (...) and contiguous subcarriers (n_sc,): shape (..., n_sc).

    A delay τ is ``phase_ramp(τ, p, 1/Δf)``, a lag of d samples ``phase_ramp(d, p, N)``.
    p = p0 + B·a + c factors the exponential into two short ones, so only
    (A + B) exponentials per shift are evaluated instead of n_sc.
    """
    p0, n = _contiguous(subcarriers)
    block = max(1, int(np.sqrt(n)))
    n_blocks = -(-n // block)
    w = (-2j * np.pi / period) * np.asarray(shift, dtype=np.float64)[..., None]
    coarse = np.exp(w * (p0 + block * np.arange(n_blocks)))  # (..., A)
    fine = np.exp(w * np.arange(block))  # (..., B)
    return (coarse[..., :, None] * fine[..., None, :]).reshape(*w.shape[:-1], -1)[..., :n]


class BlockedSpectrum:
    """Evaluates Σ_p X(p)·e^{+j2πp·t/period} (B, n_sc) at arbitrary shifts t (B, K).

    The same factorization as :func:`phase_ramp`, p = p0 + B·a + c, applied to the sum:
    Σ_a e^{j2π(p0+Ba)t/T} · Σ_c X(p0+Ba+c)·e^{j2πct/T}, so one evaluation costs n_sc
    multiply-adds and 2√n_sc exponentials, with no (B, K, n_sc) temporary.
    """

    def __init__(self, values: np.ndarray, subcarriers: np.ndarray, period: float):
        p0, n = _contiguous(subcarriers)
        self.block = max(1, int(np.ceil(np.sqrt(n))))
        n_blocks = -(-n // self.block)
        padded = np.zeros((values.shape[0], n_blocks * self.block), dtype=np.complex128)
        padded[:, :n] = values
        self.blocks = padded.reshape(values.shape[0], 1, n_blocks, self.block)  # (B, 1, A, Bs)
        self.coarse = p0 + self.block * np.arange(n_blocks)
        self.period = period

    def __call__(self, shifts: np.ndarray, rows: np.ndarray | slice | None = None) -> np.ndarray:
        """The sums at ``shifts`` (B, K), or of the ``rows`` (an index (R,) or a slice) only at ``shifts``
        (R, K); None and slices read the blocks in place, an index array gathers a copy."""
        blocks = self.blocks if rows is None else self.blocks[rows]
        w = (2j * np.pi / self.period) * np.asarray(shifts, dtype=np.float64)[..., None]  # (B, K, 1)
        inner = (blocks @ np.exp(w * np.arange(self.block))[..., None])[..., 0]  # (B, K, A)
        return np.einsum("bka,bka->bk", inner, np.exp(w * self.coarse))


def to_fft_bins(grid: np.ndarray, numerology: Numerology, dtype=np.complex128) -> np.ndarray:
    """Place active-subcarrier values (..., n_sc) into FFT bins (..., N), DC-centred."""
    bins = np.zeros((*grid.shape[:-1], numerology.fft_size), dtype=dtype)
    negative = numerology.n_subcarriers // 2
    bins[..., numerology.fft_size - negative:] = grid[..., :negative]
    bins[..., :numerology.n_subcarriers - negative] = grid[..., negative:]
    return bins


def modulate(grid: np.ndarray, cp_lengths: np.ndarray, numerology: Numerology) -> np.ndarray:
    """Resource grid (..., L, n_sc) → time samples (..., Σ(N + cp_l))."""
    useful = sfft.ifft(to_fft_bins(grid, numerology), axis=-1, norm="ortho")
    flat = useful.reshape(*useful.shape[:-2], -1)
    return flat[..., cp_gather_index(cp_lengths, numerology.fft_size)]


def from_fft_bins(bins: np.ndarray, numerology: Numerology) -> np.ndarray:
    """The inverse of :func:`to_fft_bins`: FFT bins (..., N) → active subcarriers (..., n_sc).

    Two contiguous slices, not a fancy index (which is ten times slower on the last axis).
    """
    negative = numerology.n_subcarriers // 2
    return np.concatenate([bins[..., numerology.fft_size - negative:],
                           bins[..., :numerology.n_subcarriers - negative]], axis=-1)


def demodulate(samples: np.ndarray, window_starts: np.ndarray, numerology: Numerology) -> np.ndarray:
    """Cut N-sample FFT windows at ``window_starts`` (..., L) and return the grid (..., L, n_sc).

    ``window_starts`` broadcasts against the leading axes of ``samples``.
    """
    n = numerology.fft_size
    lead = samples.shape[:-1]
    starts = np.asarray(window_starts, dtype=np.int64)
    starts = np.broadcast_to(starts, (*lead, starts.shape[-1])) if starts.ndim - 1 < len(lead) else starts
    # every window is a row of the sliding-window view: one gather of whole rows
    views = sliding_window_view(samples, n, axis=-1)
    rows = np.indices(lead, sparse=True) if lead else ()
    windows = views[(*(r[..., None] for r in rows), starts)]
    spectrum = sfft.fft(windows, axis=-1, norm="ortho", overwrite_x=True, workers=-1)
    return from_fft_bins(spectrum, numerology)
