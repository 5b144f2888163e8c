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
