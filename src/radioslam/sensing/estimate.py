"""OFDM channel estimation of each beam's sensing symbols (paper §II-C eq. (4), §III-A).

The R sensing symbols are cut with their FFT windows opened ``window_offset``
samples after each symbol's nominal useful part, i.e. inside the cyclic prefix of
every echo with delay in [offset, offset + CP]. Then, per subcarrier p:

* least squares per symbol: Ĥ_q(p) = y_q(p) / x_q(p);
* combined over the R symbols with weights |x_q(p)|² (maximum-ratio combining,
  the ML estimate for AWGN): Ĥ(p) = Σ_q y_q x_q* / Σ_q |x_q|² = Z(p) / W(p).

Z is also the spectrum of the matched filter with coherent integration over the
R symbols (§III-B): its IFFT is Σ_q x̃_q^H J_i^T y_q.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from radioslam.capture import Capture, CaptureMode
from radioslam.nr.ofdm import demodulate


@dataclass(frozen=True)
class ChannelEstimate:
    """Per beam: Z = Σ_q y_q x_q*, W = Σ_q |x_q|² (B, n_sc), and the FFT window offset (B,)."""

    z: np.ndarray
    w: np.ndarray
    window_offset: np.ndarray  # samples after the nominal useful part (delay = offset + lag)

    @property
    def h(self) -> np.ndarray:
        """The combined least-squares channel estimate Ĥ = Z / W."""
        return self.z / self.w


def received_symbols(capture: Capture, window_offset: np.ndarray) -> np.ndarray:
    """y (B, R, n_sc) of the sensing symbols, FFT windows ``window_offset`` (B,) late."""
    if capture.mode is CaptureMode.GRID:
        return capture.grid
    starts = capture.useful_starts()[:, 1:] + np.asarray(window_offset)[:, None]
    return demodulate(capture.samples, starts, capture.numerology)


def estimate_channel(capture: Capture, window_offset: np.ndarray, symbols: slice = slice(None)) -> ChannelEstimate:
    """Z, W over the sensing symbols selected by ``symbols`` (all R by default)."""
    y = received_symbols(capture, window_offset)[:, symbols]
    z = (y * capture.tx_symbols(y.dtype, conjugate=True)[:, symbols]).sum(axis=1)
    w = capture.tx_energy(y.real.dtype)[:, symbols].sum(axis=1)
    return ChannelEstimate(z, w, np.asarray(window_offset, dtype=np.int64))
