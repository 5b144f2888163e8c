"""Uniform linear array: steering vector and array factor (paper eq. (1)).

a(ϑ) = [1, e^{−j2πϑ}, …, e^{−j2π(N−1)ϑ}]^T with the normalized spatial angle
ϑ = (d/λ)·sin θ; θ is measured from the array normal, counter-clockwise.
"""

from __future__ import annotations

import numpy as np


def spatial_frequency(theta_rad: np.ndarray, spacing_wavelengths: float = 0.5) -> np.ndarray:
    """ϑ = (d/λ) sin θ."""
    return spacing_wavelengths * np.sin(theta_rad)


def steering_vector(vartheta: np.ndarray, n_elements: int) -> np.ndarray:
    """a(ϑ), eq. (1): shape (..., N)."""
    n = np.arange(n_elements)
    return np.exp(-2j * np.pi * np.asarray(vartheta)[..., None] * n)


def array_response(weights: np.ndarray, vartheta: np.ndarray) -> np.ndarray:
    """w^H a(ϑ) for weights (B, N) and angles (...): shape (B, ...).

    Closed form of the geometric sum, so no (B, P, N) tensor is built.
    """
    weights = np.atleast_2d(weights)
    a = steering_vector(vartheta, weights.shape[-1])
    return np.tensordot(weights.conj(), a, axes=([-1], [-1]))


def stacked_coupling(n_elements: int, baseline_wavelengths: float, spacing_wavelengths: float = 0.5) -> np.ndarray:
    """Free-space coupling C (N, N) from element n of one ULA to element m of a parallel ULA stacked
    ``baseline_wavelengths`` away: C[m, n] = (b/d_mn)·e^{−j2π d_mn/λ}, d_mn = √(b² + ((m − n)·d)²), i.e.
    point elements with spherical spreading, normalized to 1 across the baseline (b/d) (a first-order
    model of array mutual coupling, e.g. Balanis, *Antenna Theory*, §8.7; a real housing adds paths)."""
    offset = (np.arange(n_elements)[:, None] - np.arange(n_elements)[None, :]) * spacing_wavelengths
    distance = np.sqrt(baseline_wavelengths**2 + offset**2)
    return baseline_wavelengths / distance * np.exp(-2j * np.pi * distance)
