"""Primary synchronization signal (3GPP TS 38.211 §7.4.2.2) and its SSB placement.

The NR PSS is a length-127 BPSK m-sequence:
    x(i+7) = (x(i+4) + x(i)) mod 2,  [x(6) … x(0)] = [1 1 1 0 1 1 0],
    d(n) = 1 − 2·x((n + 43·N_ID2) mod 127).
The paper (§III-A) calls its PSS a Zadoff–Chu sequence, as LTE's was; that
variant is offered too (length 127, roots 25/29/34 for N_ID2 = 0/1/2).

Placement: the PSS occupies SSB subcarriers 56…182 (38.211 Table 7.4.3.1-1). The
SSB is centred on the carrier so that the PSS sits on subcarriers −63…63: its
15.24 MHz fit the 30.72 MSps left after decimating by 4 (paper §III-C).
"""

from __future__ import annotations

import numpy as np

from radioslam.config import PssKind

PSS_LENGTH = 127
ZC_ROOTS = (25, 29, 34)


def _m_sequence() -> np.ndarray:
    x = np.zeros(PSS_LENGTH + 7, dtype=np.int64)
    x[:7] = [0, 1, 1, 0, 1, 1, 1]  # x(0) … x(6)
    for i in range(PSS_LENGTH):  # 127-step LFSR recursion; not a sample loop
        x[i + 7] = (x[i + 4] + x[i]) % 2
    return x[:PSS_LENGTH]


_X = _m_sequence()


def pss(n_id2: int) -> np.ndarray:
    """The 127 ±1 values d_PSS(n) of 38.211 §7.4.2.2 for N_ID2 ∈ {0, 1, 2}."""
    if n_id2 not in (0, 1, 2):
        raise ValueError(f"N_ID2 must be 0, 1 or 2, got {n_id2}")
    m = (np.arange(PSS_LENGTH) + 43 * n_id2) % PSS_LENGTH
    return (1 - 2 * _X[m]).astype(np.float64)


def pss_zadoff_chu(n_id2: int) -> np.ndarray:
    """Length-127 Zadoff–Chu PSS, x_u(n) = exp(−jπ·u·n·(n+1)/127)."""
    if n_id2 not in (0, 1, 2):
        raise ValueError(f"N_ID2 must be 0, 1 or 2, got {n_id2}")
    n = np.arange(PSS_LENGTH)
    return np.exp(-1j * np.pi * ZC_ROOTS[n_id2] * n * (n + 1) / PSS_LENGTH)


def pss_sequence(kind: PssKind, n_id2: int) -> np.ndarray:
    """The PSS of the configured kind, complex."""
    seq = pss(n_id2) if kind is PssKind.M_SEQUENCE else pss_zadoff_chu(n_id2)
    return seq.astype(np.complex128)


def pss_subcarrier_indices() -> np.ndarray:
    """Signed subcarrier indices −63…63 of the centred PSS."""
    return np.arange(PSS_LENGTH) - PSS_LENGTH // 2


def pss_grid(kind: PssKind, n_id2: int, subcarriers: np.ndarray) -> np.ndarray:
    """The PSS symbol on the active subcarriers ``subcarriers`` (zeros off the PSS)."""
    grid = np.zeros(len(subcarriers), dtype=np.complex128)
    pos = np.searchsorted(subcarriers, pss_subcarrier_indices())
    grid[pos] = pss_sequence(kind, n_id2)
    return grid
