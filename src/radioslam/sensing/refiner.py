"""The peak refiner (T2): one of the refinements of :class:`~radioslam.sensing.config.Refinement`,
built from the sensing config, so that the detectors never name an algorithm."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from radioslam.sensing.bisection import RefinedPeaks, bisect_peaks, iterations_for
from radioslam.sensing.bracketed import bracketed_peaks, bracketed_track
from radioslam.sensing.config import Refinement, SensingConfig
from radioslam.sensing.profile import RangeSpectrum


@dataclass(frozen=True)
class PeakRefiner:
    """Refines integer peaks with ``method`` to ``precision`` samples, in at most ``max_steps`` steps."""

    method: Refinement
    precision: float
    max_steps: int

    @classmethod
    def from_config(cls, cfg: SensingConfig, cell_m: float) -> "PeakRefiner":
        """``cfg.precision_m`` in range, ``cell_m`` the range of one sample."""
        return cls(cfg.refine, cfg.precision_m / cell_m, cfg.max_iterations)

    @property
    def bisection_steps(self) -> int:
        return iterations_for(self.precision, self.max_steps)

    def refine(self, spec: RangeSpectrum, peaks: np.ndarray, values: np.ndarray,
               active: np.ndarray | None = None) -> RefinedPeaks:
        """Integer peak lags (B, K), F at peak − 1, peak, peak + 1 (B, K, 3): the refined peaks of the
        ``active`` ones (default: all; the others keep their integer lag)."""
        if self.method is Refinement.PAPER_BISECTION:
            return bisect_peaks(spec, peaks, values, self.bisection_steps, active)
        return bracketed_peaks(spec, peaks, values, self.precision, self.max_steps, active)

    def track(self, spec: RangeSpectrum, lag: np.ndarray) -> RefinedPeaks:
        """Re-refine paths (B,) near their previous lags after the other paths were cancelled (RELAX):
        refined peaks (B, 1). The paper's bisection restarts from the best of the three integer lags
        around the previous one; the bracketed refinement stays within half a sample of it."""
        if self.method is Refinement.PAPER_BISECTION:
            b = len(lag)
            centre = np.round(lag).astype(np.int64)
            around = spec.at((centre[:, None] + np.arange(-2, 3)).astype(np.float64))  # (B, 5)
            best = 1 + np.argmax(np.abs(around[:, 1:4]), axis=1)  # the integer peak among the 3 central
            values = np.stack([around[np.arange(b), best + d] for d in (-1, 0, 1)], axis=1)
            refined = bisect_peaks(spec, (centre + best - 2)[:, None], values[:, None, :], self.bisection_steps)
            return RefinedPeaks(refined.lag, refined.amplitude, refined.dft_evaluations + 5 * b)
        return bracketed_track(spec, lag, self.precision, self.max_steps)
