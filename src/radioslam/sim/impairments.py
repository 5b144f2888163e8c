"""Hardware impairments of the simulated front end (issue #13, point 5), each off by default
(:class:`~radioslam.config.Impairments`, the ``impairments:`` block of a scene's ``radio:``).

* **Receiver I/Q imbalance** (Tarighat et al., IEEE Trans. SP 2005): the Q rail has gain g and a
  quadrature error φ relative to I, so the baseband signal x becomes y = μ·x + ν·x̄ with
  μ = (1 + g·e^{−jφ})/2 and ν = (1 − g·e^{jφ})/2. A tone at +f leaves an image at −f whose power is
  1/IRR of it, IRR = |μ|²/|ν|² = (1 + 2g·cos φ + g²)/(1 − 2g·cos φ + g²). In the range profile the
  image is the conjugate spectrum mirrored about DC: a ghost of every echo, IRR below it, spread in
  delay (a mirrored spectrum is not a delayed one).
* **ADC quantization and clipping** (Widrow & Kollár, *Quantization Noise*, 2008): each rail is
  quantized by a b-bit mid-rise uniform quantizer whose full scale A sits ``adc_backoff_db`` above that
  rail's RMS σ (an AGC per beam window); values beyond ±A clip. The quantization noise is uniform,
  Δ²/12 with Δ = 2A/2^b, so SQNR = 6.02·b + 4.77 − backoff dB while clipping is rare; for a
  Gaussian-like OFDM rail the clipped tails add 2σ²[(1 + a²)Q(a) − a·φ(a)], a = A/σ (−51 dB at a
  12 dB backoff: past 8 bits there, more bits buy nothing). The strong TX→RX leakage takes most of
  the range: the echoes' SNR is what is left below it.
* **Per-element gain and phase errors** of both arrays (:func:`radioslam.antenna.codebook.element_responses`):
  element n of the TX and of the RX array responds with (1 + ε_g)·e^{jε_φ} instead of 1, ε drawn once
  from ``element_seed`` (they belong to the hardware, not to a capture). The beams' sidelobes rise and
  their peaks shift: the two-way gain is |w^H(e_T∘a)|·|w^H(e_R∘a)| instead of |w^H a|².
* **PA compression** (Rapp 1991): the transmitter's amplifier maps an input amplitude A to
  A / (1 + (A/A_sat)^{2p})^{1/(2p)}, phase untouched (a solid-state PA's AM/PM is small), with A_sat
  ``pa_backoff_db`` above the burst's RMS. Memoryless, it keeps each OFDM symbol cyclic, so the
  distorted symbol is still one spectrum: its active subcarriers are what the channel carries (the
  out-of-band products fall outside them). By Bussgang's theorem the in-band output is α·x plus a
  distortion uncorrelated with x: the receiver, which divides by the symbols it sent, sees a gain
  α and a noise floor.
* **Hardware-delay drift** (``hardware_delay_drift_s``, in the simulator and
  :func:`radioslam.sim.calibration_targets.plate_simulator`): T_H changes by δ between the
  calibration of eq. (11) and the captures sensed with it, so every range moves by c·δ/2 (3 cm per
  200 ps), a bias no averaging removes.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.fft as sfft

from radioslam.config import Impairments
from radioslam.nr.numerology import Numerology
from radioslam.nr.ofdm import from_fft_bins, to_fft_bins


def iq_coefficients(gain_db: float, phase_deg: float) -> tuple[complex, complex]:
    """(μ, ν) of the receiver's I/Q imbalance: y = μ·x + ν·x̄."""
    g, phi = 10.0 ** (gain_db / 20.0), np.radians(phase_deg)
    return complex((1.0 + g * np.exp(-1j * phi)) / 2.0), complex((1.0 - g * np.exp(1j * phi)) / 2.0)


def image_rejection_db(gain_db: float, phase_deg: float) -> float:
    """IRR = |μ|²/|ν|² in dB (infinite for a balanced receiver)."""
    mu, nu = iq_coefficients(gain_db, phase_deg)
    return float(10.0 * np.log10(abs(mu) ** 2 / abs(nu) ** 2)) if abs(nu) > 0 else float("inf")


def apply_iq_imbalance(samples: np.ndarray, gain_db: float, phase_deg: float) -> np.ndarray:
    """y = μ·x + ν·x̄, in the samples' dtype."""
    mu, nu = iq_coefficients(gain_db, phase_deg)
    return (mu * samples + nu * np.conj(samples)).astype(samples.dtype, copy=False)


def quantization_snr_db(bits: int, backoff_db: float) -> float:
    """SQNR of a b-bit rail with full scale ``backoff_db`` above its RMS, clipping neglected."""
    return 20.0 * np.log10(2.0) * bits + 10.0 * np.log10(3.0) - backoff_db


def gaussian_adc_snr_db(bits: int, backoff_db: float) -> float:
    """SNR of a b-bit rail for a Gaussian signal (OFDM is nearly one), clipping included: the
    quantization noise Δ²/12 plus the clipped tails' power 2σ²[(1 + a²)Q(a) − a·φ(a)], a = A/σ."""
    a = 10.0 ** (backoff_db / 20.0)
    step = 2.0 * a / 2**bits
    tail = 0.5 * math.erfc(a / math.sqrt(2.0))
    density = math.exp(-0.5 * a * a) / math.sqrt(2.0 * math.pi)
    clipped = 2.0 * ((1.0 + a * a) * tail - a * density)
    return float(-10.0 * np.log10(step**2 / 12.0 + clipped))


def quantize(samples: np.ndarray, bits: int, backoff_db: float) -> np.ndarray:
    """Each rail of each row (a beam window, (B, T)) through a b-bit mid-rise quantizer whose full
    scale A is ``backoff_db`` above that rail's RMS; beyond ±A it clips."""
    rails = np.stack([samples.real, samples.imag]).astype(np.float64)  # (2, B, T)
    rms = np.sqrt(np.mean(rails**2, axis=-1, keepdims=True))
    full_scale = rms * 10.0 ** (backoff_db / 20.0)
    step = 2.0 * full_scale / 2**bits
    with np.errstate(divide="ignore", invalid="ignore"):
        level = np.clip(np.floor(rails / step), -(2 ** (bits - 1)), 2 ** (bits - 1) - 1)
    quantized = np.where(step > 0, (level + 0.5) * step, 0.0)
    return (quantized[0] + 1j * quantized[1]).astype(samples.dtype)


def rapp(amplitude: np.ndarray, saturation: float | np.ndarray, smoothness: float) -> np.ndarray:
    """Rapp's AM/AM: A / (1 + (A/A_sat)^{2p})^{1/(2p)}."""
    ratio = amplitude / saturation
    return amplitude / (1.0 + ratio ** (2.0 * smoothness)) ** (1.0 / (2.0 * smoothness))


def compress(symbols: np.ndarray, numerology: Numerology, backoff_db: float, smoothness: float) -> np.ndarray:
    """Frequency-domain symbols (..., L, n_sc) through a Rapp PA in time (A_sat ``backoff_db`` above the
    RMS of each burst, the last two axes): the distorted symbols' active subcarriers."""
    time = sfft.ifft(to_fft_bins(symbols, numerology), axis=-1, norm="ortho")
    rms = np.sqrt(np.mean(np.abs(time) ** 2, axis=(-2, -1), keepdims=True))
    amplitude = np.abs(time)
    scale = np.divide(rapp(amplitude, rms * 10.0 ** (backoff_db / 20.0), smoothness), amplitude,
                      out=np.ones_like(amplitude), where=amplitude > 0)
    distorted = sfft.fft(time * scale, axis=-1, norm="ortho")
    return from_fft_bins(distorted, numerology).astype(symbols.dtype)


def transmitter_chain(symbols: np.ndarray, numerology: Numerology, impairments: Impairments) -> np.ndarray:
    """What the transmitter radiates of the symbols (..., L, n_sc): the PA's compression, if any."""
    if impairments.pa_backoff_db is None:
        return symbols
    return compress(symbols, numerology, impairments.pa_backoff_db, impairments.pa_smoothness)


def receiver_chain(samples: np.ndarray, impairments: Impairments) -> np.ndarray:
    """The received waveform (B, T), thermal noise included, through the mixer's I/Q imbalance and
    then the ADC (the order of a real receiver)."""
    out = samples
    if impairments.iq_gain_db != 0.0 or impairments.iq_phase_deg != 0.0:
        out = apply_iq_imbalance(out, impairments.iq_gain_db, impairments.iq_phase_deg)
    if impairments.adc_bits is not None:
        out = quantize(out, impairments.adc_bits, impairments.adc_backoff_db)
    return out
