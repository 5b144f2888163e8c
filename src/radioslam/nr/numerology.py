"""NR numerology at the prototype's sampling rate (3GPP TS 38.211 §4.2, §5.3.1).

With 120 kHz subcarrier spacing (μ = 3) and a 1024-point FFT the sample rate is
122.88 MSps. The normal cyclic prefix is 144·κ·2^-μ·T_c, i.e. 144/2048 of the FFT
size (72 samples); the first symbol of every half subframe (l = 0 and l = 7·2^μ)
gets 16·κ·T_c more (64 samples), so a 1 ms subframe is exactly 122 880 samples.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from radioslam.config import RadioConfig

SYMBOLS_PER_SLOT = 14
KAPPA = 64  # T_s / T_c, 38.211 §4.1
TC_PER_SECOND = 480e3 * 4096  # 1 / T_c


class NumerologyError(ValueError):
    """An unsupported subcarrier spacing or FFT size."""


@dataclass(frozen=True)
class Numerology:
    """Subcarrier spacing μ, FFT size, active subcarriers and CP lengths."""

    fft_size: int
    n_subcarriers: int
    subcarrier_spacing_hz: float

    @classmethod
    def from_config(cls, radio: RadioConfig) -> "Numerology":
        return cls(radio.fft_size, radio.n_subcarriers, radio.subcarrier_spacing_hz)

    def __post_init__(self) -> None:
        mu = math.log2(self.subcarrier_spacing_hz / 15e3)
        if mu != int(mu) or not 0 <= mu <= 6:
            raise NumerologyError(f"subcarrier spacing {self.subcarrier_spacing_hz} Hz is not 15·2^μ kHz")
        if (KAPPA * 144 * self.fft_size) % 2048 or (16 * KAPPA * self.fft_size * 2**int(mu)) % 131072:
            raise NumerologyError(f"FFT size {self.fft_size} gives a fractional cyclic prefix")

    @property
    def mu(self) -> int:
        return int(round(math.log2(self.subcarrier_spacing_hz / 15e3)))

    @property
    def sample_rate_hz(self) -> float:
        return self.fft_size * self.subcarrier_spacing_hz

    @property
    def symbols_per_subframe(self) -> int:
        return SYMBOLS_PER_SLOT * 2**self.mu

    @property
    def cp_normal(self) -> int:
        """144·κ·2^-μ T_c in samples (72 at μ = 3, N = 1024)."""
        return 144 * self.fft_size // 2048

    @property
    def cp_extra(self) -> int:
        """16·κ T_c in samples, added at l = 0 and l = 7·2^μ (64 at μ = 3, N = 1024)."""
        return 16 * KAPPA * self.fft_size * 2**self.mu // 131072

    def cp_lengths(self, symbol_indices: np.ndarray) -> np.ndarray:
        """CP length in samples of each absolute symbol index (38.211 §5.3.1)."""
        in_subframe = np.asarray(symbol_indices) % self.symbols_per_subframe
        long_cp = (in_subframe == 0) | (in_subframe == 7 * 2**self.mu)
        return self.cp_normal + self.cp_extra * long_cp.astype(np.int64)

    def subcarrier_indices(self) -> np.ndarray:
        """Signed subcarrier index p of each active subcarrier, DC-centred: -396 … 395.

        This is k + k0 - N_grid/2 of 38.211 §5.3.1 with k0 = 0.
        """
        half = self.n_subcarriers // 2
        return np.arange(-half, self.n_subcarriers - half)

    def fft_bins(self) -> np.ndarray:
        """FFT bin of each active subcarrier."""
        return self.subcarrier_indices() % self.fft_size
