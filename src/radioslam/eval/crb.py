"""Cramér–Rao bound on delay and range for a single path (Kay, Fundamentals of Statistical
Signal Processing I, §3.11; the OFDM radar form of Braun, PhD thesis KIT 2014, §4.3).

Observations y_{p,q} = b·e^{−j2πpΔfτ}·x_{p,q} + z on n_sc contiguous subcarriers and R
symbols, unit-energy data, unknown complex b, per-RE SNR γ = |b|²/σ². With the
amplitude's phase as a nuisance parameter the Fisher information for τ is
2γR·(2πΔf)²·Σ_p (p − p̄)², and Σ_p (p − p̄)² = n_sc(n_sc² − 1)/12, so

    var(τ̂) ≥ 1 / (8π²·Δf²·γ·R·n_sc(n_sc² − 1)/12),     σ_R = (c/2)·σ_τ.
"""

from __future__ import annotations

import numpy as np

from radioslam.config import SPEED_OF_LIGHT


def delay_crb_s(n_subcarriers: int, spacing_hz: float, symbols: int, snr_db) -> np.ndarray:
    """Standard deviation bound (s) on the delay of a single path."""
    gamma = 10.0 ** (np.asarray(snr_db, dtype=np.float64) / 10.0)
    spread = n_subcarriers * (n_subcarriers**2 - 1) / 12.0
    return 1.0 / np.sqrt(8.0 * np.pi**2 * spacing_hz**2 * gamma * symbols * spread)


def range_crb_m(n_subcarriers: int, spacing_hz: float, symbols: int, snr_db) -> np.ndarray:
    """Standard deviation bound (m) on the monostatic range of a single path."""
    return 0.5 * SPEED_OF_LIGHT * delay_crb_s(n_subcarriers, spacing_hz, symbols, snr_db)
