"""Per-beam channel frequency response on the active subcarriers (paper eq. (4)).

H_i(p) = Σ_k ϖ_{i,k} b_k e^{−j2π p Δf τ_k}; the waveform synthesizer also needs
it split by the integer sample at which each path's symbol boundaries arrive.
"""

from __future__ import annotations

import numpy as np

from radioslam.antenna.codebook import BeamSet
from radioslam.nr.ofdm import phase_ramp
from radioslam.sim.paths import EchoPaths, PathKind


def delay_phasors(delays_s: np.ndarray, subcarriers: np.ndarray, spacing_hz: float) -> np.ndarray:
    """e^{−j2π p Δf τ} for delays (P,) and contiguous subcarriers (n_sc,): shape (P, n_sc)."""
    return phase_ramp(delays_s, subcarriers, 1.0 / spacing_hz)


def beam_path_gains(beams: BeamSet, paths: EchoPaths) -> np.ndarray:
    """Complex gain ϖ_{i,k}·b_k of every path on every beam, shape (B, P); the leakage's ϖ is the
    beam's TX→RX coupling (:meth:`~radioslam.antenna.codebook.BeamSet.coupling`)."""
    leak = paths.kind == PathKind.LEAKAGE
    gain = np.empty((len(beams), len(paths)), dtype=np.complex128)
    gain[:, leak] = beams.coupling()[:, None]
    gain[:, ~leak] = beams.two_way_gain(paths.angle[~leak])
    return gain * paths.amplitude[None, :]


def strongest_echo(beams: BeamSet, paths: EchoPaths, beam: int) -> int:
    """Index of the path with the largest |ϖ·b| on ``beam``, leakage excluded."""
    gain = np.abs(beam_path_gains(beams, paths)[beam])
    gain[paths.kind == PathKind.LEAKAGE] = 0.0
    return int(np.argmax(gain))


def channel_response(gains: np.ndarray, delays_s: np.ndarray, subcarriers: np.ndarray,
                     spacing_hz: float) -> np.ndarray:
    """H (B, n_sc) from per-beam path gains (B, P) and path delays (P,)."""
    return gains @ delay_phasors(delays_s, subcarriers, spacing_hz)


def binned_channel_response(gains: np.ndarray, delays_samples: np.ndarray, subcarriers: np.ndarray,
                            spacing_hz: float, sample_rate_hz: float, row_blocks: int = 1):
    """Channel split by arrival bin d_k = ⌈τ_k·f_s − 1e-9⌉ (a path within 1e-9 sample of a
    sample instant counts as arrived there, so round-off in τ·f_s cannot move a gate).

    Returns (d_min, d_max, cumulative) with cumulative[:, m] = Σ_{k: d_k ≤ d_min+m} of the
    paths' responses, for m = 0 … d_max − d_min (the last one is the full H).
    ``row_blocks`` equal blocks of rows (the orientations) each skip the paths that
    have zero gain on all of their beams (those behind that orientation's array).
    """
    order = np.argsort(delays_samples, kind="stable")
    delays_samples, gains = delays_samples[order], gains[:, order]
    d = np.ceil(delays_samples - 1e-9).astype(np.int64)
    d_min, d_max = int(d[0]), int(d[-1])
    phasors = delay_phasors(delays_samples / sample_rate_hz, subcarriers, spacing_hz)
    cumulative = np.empty((gains.shape[0], d_max - d_min + 1, len(subcarriers)), dtype=np.complex128)
    bins = np.arange(d_min, d_max + 2)
    for rows in np.array_split(np.arange(gains.shape[0]), row_blocks):  # orientations (4)
        cols = np.flatnonzero(np.any(gains[rows] != 0, axis=0))
        g, e = gains[np.ix_(rows, cols)], phasors[cols]
        edges = np.searchsorted(d[cols], bins)  # paths of bin m: edges[m] … edges[m+1]
        running = np.zeros((len(rows), len(subcarriers)), dtype=np.complex128)
        for m in range(d_max - d_min + 1):  # one matmul per delay bin (tens); paths stay vectorized
            lo, hi = edges[m], edges[m + 1]
            if hi > lo:
                running = running + g[:, lo:hi] @ e[lo:hi]
            cumulative[rows, m] = running
    return d_min, d_max, cumulative
