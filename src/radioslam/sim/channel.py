"""Per-beam channel frequency response on the active subcarriers (paper eq. (4)).

H_i(p) = Σ_k ϖ_{i,k} b_k e^{−j2π p Δf τ_k}; the waveform synthesizer also needs
it split by the integer sample at which each path's symbol boundaries arrive.
"""

from __future__ import annotations

from functools import cache

import numpy as np
from scipy.special import gamma

from radioslam.antenna.codebook import BeamSet
from radioslam.nr.ofdm import phase_ramp
from radioslam.sim.paths import EchoPaths, PathKind


def delay_phasors(delays_s: np.ndarray, subcarriers: np.ndarray, spacing_hz: float) -> np.ndarray:
    """e^{−j2π p Δf τ} for delays (P,) and contiguous subcarriers (n_sc,): shape (P, n_sc)."""
    return phase_ramp(delays_s, subcarriers, 1.0 / spacing_hz)


def beam_path_gains(beams: BeamSet, paths: EchoPaths) -> np.ndarray:
    """Complex gain ϖ_{i,k}·b_k of every path on every beam, shape (B, P) (a backend's own ``beam_gain``
    where it gives one); the leakage's ϖ is the beam's TX→RX coupling
    (:meth:`~radioslam.antenna.codebook.BeamSet.coupling`)."""
    leak = paths.kind == PathKind.LEAKAGE
    # the leakage's angle is NaN: its column is overwritten below
    elevation = None if paths.elevation is None else np.where(leak, 0.0, paths.elevation)
    gain = (beams.two_way_gain(np.where(leak, 0.0, paths.angle), elevation, paths.row) if paths.beam_gain is None
            else paths.beam_gain.astype(np.complex128)) * paths.amplitude
    gain[:, leak] = beams.coupling()[:, None] * paths.amplitude[leak]
    return gain


def strongest_echo(beams: BeamSet, paths: EchoPaths, beam: int) -> int:
    """Index of the path with the largest |ϖ·b| on ``beam``, leakage excluded."""
    gain = np.abs(beam_path_gains(beams, paths)[beam])
    gain[paths.kind == PathKind.LEAKAGE] = 0.0
    return int(np.argmax(gain))


def channel_response(gains: np.ndarray, delays_s: np.ndarray, subcarriers: np.ndarray,
                     spacing_hz: float) -> np.ndarray:
    """H (B, n_sc) from per-beam path gains (B, P) and path delays (P,)."""
    return gains @ delay_phasors(delays_s, subcarriers, spacing_hz)


TAYLOR_TOLERANCE = 1e-8  # bound on the truncated series, relative to each path's gain


def taylor_terms(bound: float) -> int:
    """Smallest K with bound^K/K! ≤ TAYLOR_TOLERANCE: the remainder of e^{jx} after K terms, |x| ≤ bound."""
    count, remainder = 1, bound
    while remainder > TAYLOR_TOLERANCE:
        count += 1
        remainder *= bound / count
    return count


def binned_channel_response(gains: np.ndarray, delays_samples: np.ndarray, subcarriers: np.ndarray,
                            spacing_hz: float, sample_rate_hz: float, row_blocks: int = 1):
    """Channel split by arrival bin d_k = ⌈τ_k·f_s − 1e-9⌉ (a path within 1e-9 sample of a
    sample instant counts as arrived there, so round-off in τ·f_s cannot move a gate).

    Returns (d_min, d_max, cumulative): cumulative[m] (B, n_sc) = Σ_{k: d_k ≤ d_min+m} of the
    paths' responses, complex64, for m = 0 … d_max − d_min (the last one is the full H).

    A path's phasor splits as e^{−j2πp·τ_k f_s/N} = e^{−j2πp(d_k − ½)/N} · e^{j2πp·u_k/N} with
    u_k = d_k − τ_k f_s − ½ ∈ [−½, ½). The first factor is common to the bin; the second has a
    phase of at most π·max|p|/N (1.2 rad), so its Taylor series Σ_t (j2πp/N)^t/t!·u_k^t converges
    to 1e-8 in K = 12 terms. A bin's response is then Σ_t c_t(p)·μ_t with the moments
    μ_t = Σ_k ϖ_k·u_k^t: B·P·K + B·M·K·n_sc operations instead of B·P·n_sc, and exact to single
    precision. ``row_blocks`` equal blocks of rows (the orientations) each skip the paths with
    zero gain on all of their beams.
    """
    n = int(round(sample_rate_hz / spacing_hz))  # the FFT size N
    if np.any(np.diff(delays_samples) < 0):  # sorted already when the paths come by delay
        order = np.argsort(delays_samples, kind="stable")
        delays_samples, gains = delays_samples[order], gains[:, order]
    d = np.ceil(delays_samples - 1e-9).astype(np.int64)
    d_min, d_max = int(d[0]), int(d[-1])
    terms = taylor_terms(np.pi * np.abs(subcarriers).max() / n)
    powers = np.cumprod(np.repeat((d - delays_samples - 0.5)[:, None], terms, axis=1), axis=1)
    powers[:, 1:], powers[:, 0] = powers[:, :-1], 1.0  # u_k^t (P, K)
    moments = np.zeros((d_max - d_min + 1, gains.shape[0], terms), dtype=np.complex128)
    bins = np.arange(d_min, d_max + 2)
    for rows in np.array_split(np.arange(gains.shape[0]), row_blocks):  # orientations (4)
        cols = np.flatnonzero(np.any(gains[rows] != 0, axis=0))
        g, u = gains[np.ix_(rows, cols)], powers[cols]
        edges = np.searchsorted(d[cols], bins)  # paths of bin m: edges[m] … edges[m+1]
        for m in np.flatnonzero(edges[1:] > edges[:-1]):  # one small matmul per occupied delay bin
            moments[m, rows] = g[:, edges[m]:edges[m + 1]] @ u[edges[m]:edges[m + 1]]
    t = np.arange(terms)[:, None]
    series = (1j ** t * (2 * np.pi * subcarriers / n) ** t / gamma(t + 1)).astype(np.complex64)  # c_t(p) (K, n_sc)
    per_bin = (moments.astype(np.complex64).reshape(-1, terms) @ series).reshape(*moments.shape[:2], -1)
    per_bin *= unit_roots(-(2 * bins[:-1] - 1), subcarriers, 2 * n)[:, None, :]  # e^{−j2πp(d − ½)/N}
    for m in range(1, len(per_bin)):  # running sum over the bins (tens), each a (B, n_sc) slab
        per_bin[m] += per_bin[m - 1]
    return d_min, d_max, per_bin


def unit_roots(shifts: np.ndarray | int, subcarriers: np.ndarray, n: int) -> np.ndarray:
    """e^{+j2πp·s/N} for integer shifts s (...) and subcarriers (n_sc,), complex64 (..., n_sc), exact:
    looked up at (p·s mod N) in a table of the N roots of unity, so large s lose no precision."""
    index = np.multiply.outer(np.asarray(shifts, dtype=np.int64), np.asarray(subcarriers, dtype=np.int64)) % n
    return _roots_of_unity(n)[index]


@cache
def _roots_of_unity(n: int) -> np.ndarray:
    """e^{j2πk/N}, k = 0 … N−1, complex64 (built once per N: the synthesis asks for it per block)."""
    table = np.exp(2j * np.pi * np.arange(n) / n).astype(np.complex64)
    table.flags.writeable = False
    return table
