"""Oscillator phase noise of the simulated front end (issue #13, point 5), off by default.

Model: the LO's phase is a Wiener process (a free-running oscillator's phase diffusion, Demir,
Mehrotra & Roychowdhury, IEEE TCAS-I 2000): E[(φ(t + τ) − φ(t))²] = 2π·Δf·|τ| with Δf the 3 dB
linewidth of its Lorentzian spectrum, so the single-sideband noise far from the carrier is
L(f) ≈ Δf/(π f²).

What cancels in a monostatic terminal. The transmitter radiates s(t)·e^{jφ(t)}; an echo arrives
τ later and the receiver mixes it down with the same LO, e^{−jφ(t)}: what is left is
e^{j(φ(t − τ) − φ(t))}, whose variance is 2π·Δf·τ, growing with the echo's range only. A
28 GHz PLL with −90 dBc/Hz at 100 kHz offset has Δf ≈ π·f²·L(f) ≈ 31 Hz: at 40 m (τ = 267 ns)
the residual is 5·10⁻⁵ rad², −43 dB: nothing. Two separate LOs (``oscillators: separate``)
leave φ_T(t − τ) − φ_R(t), which wanders by 2π·Δf per second of capture on top: that is
what a shared LO buys. Only the radio-frequency delay decorrelates: the hardware delay T_H is
modelled as the digital chain's latency (buffers, filters), during which the LO is the same at
both ends, so the transmitted sample u meets the LO phase φ(u) and the received sample n the
phase φ(n − T_H·f_s).

The TX side is applied per OFDM symbol, as if the symbol were cyclic (its CP carries the phase of
the symbol's end, not of the instant before its start): exact while 2π·Δf·(N + CP)/f_s ≪ 1,
which the configuration's bound (1 kHz: 0.056 rad²) keeps. Sub-sample delays see the phase of
the nearest sample (2π·Δf/f_s = 5·10⁻⁸ rad² per sample at 1 kHz).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.fft as sfft

from radioslam.config import Oscillators
from radioslam.nr.numerology import Numerology
from radioslam.nr.ofdm import from_fft_bins, symbol_starts, to_fft_bins


def wiener_phase(rng: np.random.Generator, shape: tuple[int, int], linewidth_hz: float,
                 sample_rate_hz: float) -> np.ndarray:
    """Phase (B, T) radians at the sample instants: a random walk with variance 2π·Δf/f_s per sample."""
    steps = rng.standard_normal(shape) * np.sqrt(2.0 * np.pi * linewidth_hz / sample_rate_hz)
    return np.cumsum(steps, axis=1)


@dataclass(frozen=True)
class OscillatorPhases:
    """What the transmitter's symbols and the receiver's mixer see of the LO, per beam window.

    ``tx[:, u + latency]`` is the phase the transmitted sample u is sent with, ``rx[:, n]`` the
    phase the received sample n is mixed down with (samples counted from the burst's start)."""

    tx: np.ndarray
    rx: np.ndarray
    latency: int

    @classmethod
    def draw(cls, rng: np.random.Generator, beams: int, window_length: int, latency_samples: int,
             linewidth_hz: float, sample_rate_hz: float, oscillators: Oscillators) -> "OscillatorPhases":
        # one LO: φ over [−latency, window) so that tx[u + latency] = φ(u) and rx[n] = φ(n − latency)
        tx = wiener_phase(rng, (beams, window_length + latency_samples), linewidth_hz, sample_rate_hz)
        if oscillators is Oscillators.SHARED:
            return cls(tx, tx[:, :window_length], latency_samples)
        rx = wiener_phase(rng, (beams, window_length), linewidth_hz, sample_rate_hz)
        return cls(tx, rx, latency_samples)

    def transmitted(self, symbols: np.ndarray, cp: np.ndarray, numerology: Numerology) -> np.ndarray:
        """Frequency-domain symbols (B, L, n_sc) as radiated: each useful part times e^{jφ}, back to its
        active subcarriers (ICI into them included, out-of-band products dropped)."""
        n = numerology.fft_size
        useful_start = symbol_starts(cp, n) + cp  # (B, L) from the burst's start
        index = useful_start[..., None] + np.arange(n) + self.latency  # (B, L, N)
        phase = np.take_along_axis(self.tx, index.reshape(len(index), -1), axis=1).reshape(index.shape)
        time = sfft.ifft(to_fft_bins(symbols, numerology), axis=-1, norm="ortho")
        distorted = sfft.fft(time * np.exp(1j * phase), axis=-1, norm="ortho")
        return from_fft_bins(distorted, numerology).astype(symbols.dtype)

    def received(self, samples: np.ndarray) -> np.ndarray:
        """The received windows (B, W) mixed down with the LO: times e^{−jφ}."""
        return (samples * np.exp(-1j * self.rx[:, :samples.shape[1]])).astype(samples.dtype)
