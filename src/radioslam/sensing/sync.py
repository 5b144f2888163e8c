"""Coarse synchronization on the PSS (T1), paper §III-A and §III-C.

The received window is decimated by 4 (a 4-sample moving sum, i.e. a
first-order CIC: −0.8 dB at the PSS band edge ±7.6 MHz, so the 127-subcarrier PSS
survives while the rate drops to f_s/4) and cross-correlated with the local PSS
at that rate. The correlation peak marks where the echo's PSS useful part starts;
subtracting the useful part's nominal start gives T1, the beam's delay on the
4-sample synchronization grid. The sensing symbols are then cut inside their
cyclic prefixes around T1 and the OFDM estimate refines the rest (T2).

The search spans every delay the window can hold, so a hardware delay of
thousands of samples (32 µs ≈ 3932 samples) is found without being told.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import scipy.fft as sfft

from radioslam.capture import Capture, CaptureMode
from radioslam.nr.pss import pss_grid
from radioslam.sensing.cfar import noise_floor


@dataclass(frozen=True)
class SyncResult:
    """T1 of each beam (B,) in samples at f_s, and whether the PSS was found."""

    t1_samples: np.ndarray  # int64
    found: np.ndarray  # bool
    peak_to_floor_db: np.ndarray


@lru_cache(maxsize=8)
def _replica(pss, n_id2: int, n: int) -> np.ndarray:
    """The PSS symbol's useful part at n samples (f_s/decimation), unit energy (read-only)."""
    p = np.arange(-63, 64)
    grid = np.zeros(n, dtype=np.complex128)
    grid[p % n] = pss_grid(pss, n_id2, p)
    replica = sfft.ifft(grid)
    replica /= np.linalg.norm(replica)
    replica.flags.writeable = False
    return replica


@lru_cache(maxsize=8)
def _replica_spectrum(pss, n_id2: int, n: int, size: int, dtype: np.dtype) -> np.ndarray:
    """conj(FFT) of the replica, zero-padded to ``size``, in ``dtype``: what each beam's spectrum is
    multiplied by (built once per radio and window length)."""
    spectrum = np.conj(sfft.fft(_replica(pss, n_id2, n).astype(dtype), size))
    spectrum.flags.writeable = False
    return spectrum


def coarse_sync(capture: Capture, decimation: int = 4, pfa: float = 1e-6) -> SyncResult:
    """T1 per beam from the PSS correlation of the decimated window (vectorized over beams)."""
    if capture.mode is CaptureMode.GRID:  # no PSS: the FFT timing is the capture's own
        b = capture.n_beams
        return SyncResult(np.full(b, capture.fft_offset_samples, dtype=np.int64), np.ones(b, bool), np.full(b, np.inf))
    num = capture.numerology
    useful0 = capture.useful_starts()[:, 0]  # where the PSS useful part starts if undelayed
    cp = capture.cp_lengths()
    burst = cp.sum(axis=1) + num.fft_size * cp.shape[1]
    window = capture.samples.shape[1]
    search = int(min(window, (window - burst.min()) + useful0.max() + num.fft_size))
    search -= search % decimation
    # decimate: 4-sample moving sum, every 4th sample (first-order CIC; not divided by 4, as neither the
    # peak's lag nor its ratio to the floor depends on the scale)
    samples = capture.samples[:, :search]
    low = samples[:, 0::decimation].copy()  # strided, summed in place: no slow axis mean, no temporaries
    for k in range(1, decimation):
        low += samples[:, k::decimation]
    n = num.fft_size // decimation  # the replica's length
    lags = low.shape[1] - n + 1
    if lags < 1:
        raise ValueError("window shorter than one PSS symbol")
    size = sfft.next_fast_len(low.shape[1] + n)
    spectrum = sfft.fft(low, size, axis=1, workers=-1)
    spectrum *= _replica_spectrum(capture.radio.pss, capture.radio.n_id2, n, size, low.dtype)[None]
    corr = sfft.ifft(spectrum, axis=1, overwrite_x=True, workers=-1)[:, :lags]
    power = corr.real**2 + corr.imag**2
    peak = np.argmax(power, axis=1)
    # the floor from every 4th lag: adjacent lags are correlated, and a quarter of them
    # estimate the median within a few per cent at a quarter of the cost
    floor = noise_floor(power[:, ::4])
    ratio = power[np.arange(len(peak)), peak] / np.maximum(floor, np.finfo(float).tiny)
    found = ratio > np.log(lags / pfa)
    # the block average of samples 4n…4n+3 is centred on 4n + 1.5: round to the grid point 4n + 2
    t1 = peak * decimation + decimation // 2 - useful0
    return SyncResult(t1.astype(np.int64), found, 10 * np.log10(np.maximum(ratio, 1e-30)))
