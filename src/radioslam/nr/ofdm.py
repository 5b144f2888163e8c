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


def contiguous_subcarriers(subcarriers: np.ndarray) -> tuple[int, int]:
    """The first index and the count of contiguous subcarriers (the factorizations need them)."""
    p0, n = int(subcarriers[0]), len(subcarriers)
    if not np.array_equal(subcarriers, p0 + np.arange(n)):
        raise ValueError("subcarriers must be contiguous")
    return p0, n


def _ramp_factors(shift: np.ndarray, subcarriers: np.ndarray, period: float) -> tuple[np.ndarray, np.ndarray, int]:
    """e^{−j2π·p·shift/period} = coarse[a]·fine[c] for p = p0 + B·a + c: (…, A), (…, B) and n_sc."""
    p0, n = contiguous_subcarriers(subcarriers)
    block = max(1, int(np.sqrt(n)))
    n_blocks = -(-n // block)
    w = (-2.0 * np.pi / period) * np.asarray(shift, dtype=np.float64)[..., None]
    return unit_phasors(w * (p0 + block * np.arange(n_blocks))), unit_phasors(w * np.arange(block)), n


def unit_phasors(angle: np.ndarray) -> np.ndarray:
    """e^{j·angle} of real angles, as cos + j·sin written into one complex array: the same values as
    ``np.exp(1j * angle)`` (whose complex exponential evaluates exp(0) and a complex product besides)
    in half the time."""
    out = np.empty(np.shape(angle), dtype=np.complex128)
    np.cos(angle, out=out.real)
    np.sin(angle, out=out.imag)
    return out


def phase_ramp(shift: np.ndarray, subcarriers: np.ndarray, period: float) -> np.ndarray:
    """e^{−j2π·p·shift/period} for shifts (...) and contiguous subcarriers (n_sc,): shape (..., n_sc).

    A delay τ is ``phase_ramp(τ, p, 1/Δf)``, a lag of d samples ``phase_ramp(d, p, N)``.
    p = p0 + B·a + c factors the exponential into two short ones, so only
    (A + B) exponentials per shift are evaluated instead of n_sc.
    """
    coarse, fine, n = _ramp_factors(shift, subcarriers, period)
    return (coarse[..., :, None] * fine[..., None, :]).reshape(*coarse.shape[:-1], -1)[..., :n]


def summed_phase_ramps(shift: np.ndarray, weight: np.ndarray, subcarriers: np.ndarray, period: float) -> np.ndarray:
    """Σ_k w_k·e^{−j2π·p·shift_k/period} for shifts and weights (B, K): shape (B, n_sc).

    :func:`phase_ramp`'s factors with the weights folded into the coarse one, so the sum over k
    is one product (A, K) @ (K, Bs) per row and no (B, K, n_sc) ramp is built.
    """
    coarse, fine, n = _ramp_factors(shift, subcarriers, period)
    weighted = coarse * np.asarray(weight)[..., None]  # (B, K, A)
    return (weighted.transpose(0, 2, 1) @ fine).reshape(coarse.shape[0], -1)[:, :n]


def place_in_bins(values: np.ndarray, first: int, size: int, dtype=np.complex128) -> np.ndarray:
    """Values (..., n) of the contiguous subcarriers first … first + n − 1 in ``size`` FFT bins (..., size),
    zeros elsewhere: subcarrier p in bin p mod size, by two slices (a fancy index is ten times slower)."""
    bins = np.zeros((*values.shape[:-1], size), dtype=dtype)
    count, start = values.shape[-1], first % size
    head = min(count, size - start)
    bins[..., start:start + head], bins[..., :count - head] = values[..., :head], values[..., head:]
    return bins


def to_fft_bins(grid: np.ndarray, numerology: Numerology, dtype=np.complex128) -> np.ndarray:
    """Place active-subcarrier values (..., n_sc) into FFT bins (..., N), DC-centred."""
    return place_in_bins(grid, -(numerology.n_subcarriers // 2), numerology.fft_size, dtype)


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
