"""Joint maximum-likelihood refinement of every path of a beam, in the lag domain.

The model (paper §III-B, the matched filter's spectrum): S(p) = Σ_k a_k·m(p)·e^{−jω_p t_k} + noise,
ω_p = 2πp/N, with the ML cost Σ_p |S − Σ_k a_k m e_k|² / m. The amplitudes enter linearly, so
they are solved for at every step (variable projection, Golub & Pereyra 1973) and the lags
move by Gauss–Newton on the projected Jacobian (Kaufman 1975).

Every inner product the step needs is a DFT evaluation at a lag, so nothing of size
(B, M, n_sc) is ever built:

* ⟨e_i, S⟩ = Σ_p S e^{jω t_i} and its lag derivative: the spectrum's sums at t_i;
* the Gram matrix G_ij = Σ_p m e_i* e_j = K(t_i − t_j), and K′, K″ at the same differences,
  K(Δ) = Σ_p m(p) e^{jω_p Δ} the model's kernel;
* with d_k = ∂(a_k m e_k)/∂t_k = −jω a_k m e_k:
  ⟨m e_i, d_k⟩/m = −a_k K′(t_i − t_k), ⟨d_k, d_l⟩/m = −a_k* a_l K″(t_k − t_l),
  ⟨d_k, r⟩/m = a_k* (S′(t_k) − Σ_l a_l K′(t_k − t_l)).

The model is real, so K(−Δ) = K(Δ)*, K′(−Δ) = −K′(Δ)*, K″(−Δ) = K″(Δ)*: only the pairs
i < j are evaluated. One step costs 2M + 3·M(M−1)/2 evaluations of n_sc terms per beam.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from radioslam.sensing.profile import RangeSpectrum

MAX_STEP = 0.25  # samples per Gauss–Newton step: well inside the main lobe (≥ 2.6 samples null to null)
RIDGE = 1e-9  # relative diagonal load, so two paths that met at one lag stay solvable


def ridge(matrix: np.ndarray) -> np.ndarray:
    """``matrix`` (B, M, M) with a ``RIDGE`` relative diagonal load."""
    load = RIDGE * np.abs(np.trace(matrix, axis1=1, axis2=2))[:, None, None] / matrix.shape[1]
    return matrix + load * np.eye(matrix.shape[1])[None]


@lru_cache(maxsize=16)
def pairs(m: int) -> tuple[np.ndarray, np.ndarray]:
    """The index pairs i < j of m paths (``np.triu_indices(m, 1)``, built once per m, read-only)."""
    upper, lower = np.triu_indices(m, 1)
    upper.flags.writeable = lower.flags.writeable = False
    return upper, lower


@dataclass(frozen=True)
class PairKernels:
    """K, K′, K″ (B, M, M) at every lag difference t_i − t_j of a beam's paths (K′, K″: None when not
    asked for)."""

    k0: np.ndarray
    k1: np.ndarray | None = None
    k2: np.ndarray | None = None

    @classmethod
    def at(cls, spec: RangeSpectrum, lag: np.ndarray, rows: np.ndarray | None = None,
           order: int = 2) -> "PairKernels":
        """Up to the ``order``-th derivative, at the lags (B, M) of every beam of ``spec``, or (R, M) of its
        ``rows`` (R,)."""
        b, m = lag.shape
        upper, lower = pairs(m)
        values = spec.kernel_with_derivatives(lag[:, upper] - lag[:, lower], rows, order)  # (order + 1, B, pairs)
        kernels = np.empty((order + 1, b, m, m), dtype=np.complex128)
        at_zero = (spec.kernel_at_zero if rows is None else spec.kernel_at_zero[:, rows])[:order + 1]
        kernels[:, :, np.arange(m), np.arange(m)] = at_zero[:, :, None]
        kernels[:, :, upper, lower] = values
        kernels[:, :, lower, upper] = values.conj() * np.array([1.0, -1.0, 1.0])[:order + 1, None, None]
        return cls(*kernels)


def present_gram(gram: np.ndarray, present: np.ndarray) -> np.ndarray:
    """The Gram matrices (B, M, M) of the present paths, with an identity row and column for each absent one
    (its amplitude solves to 0), ridge-loaded."""
    both = present[:, :, None] & present[:, None, :]
    return ridge(np.where(both, gram, 0.0) + np.eye(gram.shape[1])[None] * (~present)[:, :, None])


def solve_amplitudes(gram: np.ndarray, rhs: np.ndarray, present: np.ndarray) -> np.ndarray:
    """Least-squares amplitudes (B, M) from the Gram matrix and ⟨e_i, S⟩; absent paths get 0."""
    return np.linalg.solve(present_gram(gram, present), (rhs * present)[..., None])[..., 0]


def joint_amplitudes(spec: RangeSpectrum, rows: np.ndarray, lag: np.ndarray, present: np.ndarray) -> np.ndarray:
    """The least-squares amplitudes (R, M) of paths at lags (R, M) on ``spec``'s ``rows`` (absent: 0)."""
    t = np.nan_to_num(lag)
    inner = spec.with_derivatives(t, rows, order=0)[0] * spec.scale[rows][:, None]  # ⟨e_i, S⟩
    return solve_amplitudes(PairKernels.at(spec, t, rows, order=0).k0, inner, present)


def gauss_newton_step(spec: RangeSpectrum, rows: np.ndarray, lag: np.ndarray, present: np.ndarray,
                      movable: np.ndarray) -> np.ndarray:
    """One variable-projection Gauss–Newton step (R, M) of the lags (R, M) of ``spec``'s ``rows`` (R,)."""
    f, f_prime = spec.with_derivatives(lag, rows, order=1) * spec.scale[rows][None, :, None]  # ⟨e_i, S⟩, ∂/∂t_i
    kern = PairKernels.at(spec, lag, rows)
    gram = present_gram(kern.k0, present)
    amp = np.linalg.solve(gram, (f * present)[..., None])[..., 0]  # :func:`solve_amplitudes`
    cross = -kern.k1 * amp[:, None, :] * present[:, :, None]  # ⟨m e_i, d_k⟩ / m
    projected = np.linalg.solve(gram, cross)  # the amplitudes' span, projected out
    hess = (-amp.conj()[:, :, None] * amp[:, None, :] * kern.k2 - cross.conj().transpose(0, 2, 1) @ projected).real
    grad = (amp.conj() * (f_prime - (kern.k1 @ amp[..., None])[..., 0])).real
    hess = hess * movable[:, :, None] * movable[:, None, :] + np.eye(lag.shape[1])[None] * (~movable)[:, :, None]
    step = np.linalg.solve(ridge(hess), (grad * movable)[..., None])[..., 0]
    return np.clip(step, -MAX_STEP, MAX_STEP)


def refine_paths(spec: RangeSpectrum, rows: np.ndarray, lag: np.ndarray, present: np.ndarray, fixed: np.ndarray,
                 precision: float, max_steps: int) -> tuple[np.ndarray, np.ndarray, int]:
    """The movable lags (R, M) of ``spec``'s ``rows`` (R,) refined jointly: Gauss–Newton steps until
    every step of a beam is below ``precision`` / 4 samples (that beam stops), or ``max_steps``.
    Returns the lags, their least-squares amplitudes and the DFT evaluations spent."""
    lag = np.where(present, lag, 0.0)
    movable = present & ~fixed[None, :]
    m = lag.shape[1]
    per_beam = 2 * m + 3 * (m * (m - 1) // 2)
    active, spent = np.flatnonzero(movable.any(axis=1)), 0
    for _ in range(max_steps):
        if not len(active):
            break
        step = gauss_newton_step(spec, rows[active], lag[active], present[active], movable[active])
        lag[active] += step
        spent += per_beam * len(active)
        active = active[np.abs(step).max(axis=1) >= precision / 4]
    amp = joint_amplitudes(spec, rows, lag, present)
    return np.where(present, lag, np.nan), amp, spent + per_beam * len(lag)
