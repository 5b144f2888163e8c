"""A range spectrum with known paths cancelled, evaluated in the lag domain (successive
cancellation, paper §III-B).

Cancelling paths (lags t_k, amplitudes a_k) from S and evaluating the residual's profile at a
lag t is evaluating the profile there and subtracting each path's kernel:
F_res(t) = F(t) − Σ_k a_k K(t − t_k) / Σ_p m, K(Δ) = Σ_p m(p) e^{jω_p Δ}, and likewise for the
lag derivatives. So the sums of S and of the model, set up once per capture, serve every
search's refinement: no residual spectrum, and no new evaluator, per search.

It answers what a refiner asks of a :class:`~radioslam.sensing.profile.RangeSpectrum`
(``at``, ``with_derivatives``, ``kernel``, ``rows``, ``beam_count``).
"""

from __future__ import annotations

import numpy as np

from radioslam.sensing.profile import RangeSpectrum


class CancelledSpectrum:
    """The beams ``beams`` (R,) of ``spec`` with paths (R, M) of lags ``lag`` and amplitudes ``amp``
    removed (a NaN lag: nothing to remove)."""

    def __init__(self, spec: RangeSpectrum, beams: np.ndarray, lag: np.ndarray, amp: np.ndarray):
        self.spec, self.beams = spec, np.asarray(beams)
        self.lag, self.amp = np.nan_to_num(lag), np.where(np.isfinite(lag), amp, 0.0)

    @property
    def beam_count(self) -> int:
        return len(self.beams)

    def rows(self, mask: np.ndarray) -> "CancelledSpectrum":
        return CancelledSpectrum(self.spec, self.beams[mask], self.lag[mask], self.amp[mask])

    def with_derivatives(self, lags: np.ndarray, rows: np.ndarray | None = None, order: int = 2) -> np.ndarray:
        """F and its lag derivatives up to ``order`` of the residual at lags (R, K): (order + 1, R, K);
        with ``rows``, of those rows only."""
        beams, lag, amp = ((self.beams, self.lag, self.amp) if rows is None else
                           (self.beams[rows], self.lag[rows], self.amp[rows]))
        r, k = lags.shape
        own = self.spec.with_derivatives(lags, beams, order)
        difference = (lags[:, :, None] - lag[:, None, :]).reshape(r, -1)  # t − t_k (R, K·M)
        kernels = self.spec.kernel_with_derivatives(difference, beams, order).reshape(order + 1, r, k, -1)
        return own - np.einsum("crkm,rm->crk", kernels, amp) / self.spec.scale[beams][:, None]

    def at(self, lags: np.ndarray) -> np.ndarray:
        return self.with_derivatives(lags, order=0)[0]

    def kernel(self, lags: np.ndarray) -> np.ndarray:
        """The model's kernel at lags (R, K): cancelling paths leaves it as it was."""
        return self.spec.kernel_with_derivatives(lags, self.beams, order=0)[0]
