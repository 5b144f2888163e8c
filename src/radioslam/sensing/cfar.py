"""CFAR thresholds on a circular power profile (Richards, Fundamentals of Radar Signal
Processing, §16.4–16.5; Rohling 1983 for the ordered statistic).

For each cell, ``train`` cells on each side beyond ``guard`` cells estimate the
noise; the threshold is α·estimate with α set for the false-alarm probability
under exponentially distributed (square-law detected Gaussian) noise:
  CA: α = n(Pfa^{−1/n} − 1) over the n = 2·train cells;
  OS: the k-th smallest of the n cells (k = ⌈3n/4⌉), α solving
      Pfa = Π_{i=0}^{k−1} (n − i)/(n − i + α).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from scipy.optimize import brentq

from radioslam.sensing.config import CfarKind


def noise_floor(power: np.ndarray) -> np.ndarray:
    """Mean noise power per row (B,), from the median of exponentially distributed cells."""
    return np.median(power, axis=-1) / np.log(2.0)


def noise_threshold(power: np.ndarray, pfa: float) -> np.ndarray:
    """(B, 1): a cell of pure noise exceeds it somewhere in the N cells of its row with probability ≈ pfa."""
    return noise_floor(power)[:, None] * np.log(power.shape[1] / pfa)


def ca_alpha(n: int, pfa: float) -> float:
    return n * (pfa ** (-1.0 / n) - 1.0)


@lru_cache(maxsize=32)
def os_alpha(n: int, k: int, pfa: float) -> float:
    def excess(alpha: float) -> float:
        i = np.arange(k)
        return float(np.sum(np.log((n - i) / (n - i + alpha))) - np.log(pfa))

    return float(brentq(excess, 1e-9, 1e9))


def training_cells(power: np.ndarray, guard: int, train: int) -> np.ndarray:
    """(B, N, 2·train) training cells of every cell of a circular profile (B, N)."""
    reach = guard + train
    wrapped = np.concatenate([power[:, -reach:], power, power[:, :reach]], axis=1)
    windows = sliding_window_view(wrapped, 2 * reach + 1, axis=1)  # (B, N, 2·reach + 1)
    return np.concatenate([windows[..., :train], windows[..., -train:]], axis=-1)


def cfar_threshold(power: np.ndarray, kind: CfarKind, guard: int, train: int, pfa: float) -> np.ndarray:
    """Detection threshold (B, N) for ``power`` (B, N)."""
    cells = training_cells(power, guard, train)
    n = cells.shape[-1]
    if kind is CfarKind.CA:
        return ca_alpha(n, pfa) * cells.mean(axis=-1)
    k = int(np.ceil(0.75 * n))
    return os_alpha(n, k, pfa) * np.partition(cells, k - 1, axis=-1)[..., k - 1]
