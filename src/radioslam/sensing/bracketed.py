"""Bracketed peak refinement (T2) that cannot step into the wrong lobe (issue #13).

The paper's bisection (:mod:`radioslam.sensing.bisection`) always halves towards the higher
integer neighbour; when that neighbour belongs to another lobe (a second echo, the leakage's
skirt) the true maximum on the other side is never looked at. Here both sides are looked at:

1. |F| is sampled on a grid of ``GRID_STEP`` = 1/4 sample over [k − 1, k + 1] around the
   integer peak k (six DFT evaluations besides the three integer lags already known).
   Every grid local maximum whose value could still become the highest after refinement
   is a contender (an end of the grid counts when it is at least its one neighbour: a lobe
   whose maximum lies between the last two samples rises to the end): a lone path off the grid
   by at most half a step keeps at least |K(step/2)| / |K(0)| of its amplitude, K the model's
   kernel (Dirichlet, or the taper's), so a lobe whose grid maximum lies further below the best
   grid value cannot win.
2. Each contender g is refined within the bracket [g − step, g + step] ∩ [k − 1, k + 1], which
   holds the lobe's highest point in the window (|F(g)| is at least |F| at both ends of the
   bracket, or g is the window's end) and, at a quarter sample, lies within one lobe (the
   main lobe is 2·N/n_sc ≥ 2.6 samples wide null to null), by safeguarded Newton iteration on
   the derivative of |F|² (``rtsafe``, Press et al., Numerical Recipes §9.4):
   d|F|²/dt = 2 Re(F̄ F′), d²|F|²/dt² = 2 (|F′|² + Re(F̄ F″)), F′ and F″ DFTs of S·jω and
   S·(jω)². The derivative's sign at each iterate keeps the bracket around the maximum; a
   Newton step that leaves it, or a point where |F|² is not concave, is replaced by the
   bracket's midpoint. Quadratic convergence: three steps take 1/8 sample to below 10⁻⁴.
3. The highest refined contender is the peak.

Vectorized over every contender: one evaluation of F, F′, F″ per Newton step
(:class:`~radioslam.nr.nufft.LagSums`).
"""

from __future__ import annotations

import numpy as np

from radioslam.sensing.bisection import RefinedPeaks
from radioslam.sensing.profile import RangeSpectrum

GRID_STEP = 0.25  # samples; well inside the main lobe (≥ 2.6 samples null to null)
MAX_CONTENDERS = 3  # grid lobes refined per peak: two main lobes fit within ±1 sample, and a third's
# rising flank can reach an end of the window


def grid_offsets() -> np.ndarray:
    """The grid's offsets from the integer peak, −1 … +1 in ``GRID_STEP`` (the integers included)."""
    return np.arange(-1.0, 1.0 + GRID_STEP / 2, GRID_STEP)


def straddle_ratio(spec: RangeSpectrum) -> np.ndarray:
    """(B,) |K(step/2)| / |K(0)|: the least fraction of a lone path's amplitude a grid sample keeps."""
    zero_half = np.broadcast_to(np.array([0.0, GRID_STEP / 2]), (spec.beam_count, 2))
    kernel = np.abs(spec.kernel(zero_half))
    return kernel[:, 1] / kernel[:, 0]


def contenders(magnitude: np.ndarray, keep: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Grid indices (A, C) of the best ``MAX_CONTENDERS`` grid local maxima per row of |F| (A, G)
    that clear ``keep`` (A,) times the row's best value, and whether each exists."""
    local = np.ones_like(magnitude, dtype=bool)  # at least each neighbour it has: the ends have one
    local[:, 1:] &= magnitude[:, 1:] >= magnitude[:, :-1]
    local[:, :-1] &= magnitude[:, :-1] >= magnitude[:, 1:]
    strong = local & (magnitude >= keep[:, None] * magnitude.max(axis=1, keepdims=True))
    ranked = np.argsort(np.where(strong, -magnitude, np.inf), axis=1, kind="stable")[:, :MAX_CONTENDERS]
    return ranked, np.take_along_axis(strong, ranked, axis=1)


def safeguarded_newton(spec: RangeSpectrum, start: np.ndarray, low: np.ndarray, high: np.ndarray,
                       precision: float, max_steps: int) -> tuple[np.ndarray, np.ndarray, int]:
    """Maximize |F| of each row of ``spec`` (R,) within [low, high] from ``start`` (inside it): the
    lags, F there and the DFT evaluations spent. Stops once every row's last step is below
    ``precision`` / 4 samples, or after ``max_steps``."""
    low, high, lag = low.astype(np.float64), high.astype(np.float64), start.astype(np.float64).copy()
    spent, active = 0, np.arange(len(lag))  # the rows still moving: a row stops once its step is below
    for _ in range(max_steps):  # precision / 4, and only the others are evaluated again
        at = lag[active]
        f, d1, d2 = spec.with_derivatives(at[:, None], None if len(active) == len(lag) else active)[..., 0]
        spent += 3 * len(active)
        slope = np.real(np.conj(f) * d1)  # ½ d|F|²/dt
        curvature = np.abs(d1) ** 2 + np.real(np.conj(f) * d2)  # ½ d²|F|²/dt²
        lo, hi = np.where(slope > 0, at, low[active]), np.where(slope > 0, high[active], at)  # the maximum lies uphill
        with np.errstate(divide="ignore", invalid="ignore"):
            newton = at - slope / curvature
        inside = (curvature < 0) & (newton >= lo) & (newton <= hi)
        moved = np.where(inside, newton, 0.5 * (lo + hi))
        low[active], high[active], lag[active] = lo, hi, moved
        active = active[np.abs(moved - at) >= precision / 4]
        if not len(active):
            break
    value = spec.at(lag[:, None])[:, 0]
    return lag, value, spent + len(lag)


def bracketed_track(spec: RangeSpectrum, lag: np.ndarray, precision: float, max_steps: int) -> RefinedPeaks:
    """Re-refine paths (B,) already refined once, after the others were cancelled (RELAX): the
    maximum of |F| within half a sample of the previous lag, so that a path never leaves its own
    lobe for a neighbour's imperfectly cancelled one (two paths would merge)."""
    refined, value, spent = safeguarded_newton(spec, lag, lag - 2 * GRID_STEP, lag + 2 * GRID_STEP, precision,
                                               max_steps)
    return RefinedPeaks(refined[:, None], value[:, None], spent)


def bracketed_peaks(spec: RangeSpectrum, peaks: np.ndarray, values: np.ndarray, precision: float, max_steps: int,
                    active: np.ndarray | None = None) -> RefinedPeaks:
    """Refine integer peak lags (B, K), given F at lags peak − 1, peak, peak + 1 (B, K, 3):
    every lobe of the ±1-sample grid that may hold the highest maximum, each within its bracket."""
    lag, value = peaks.astype(np.float64), values[..., 1].copy()
    beams, slots = np.nonzero(np.ones(peaks.shape, bool) if active is None else active)
    if len(beams) == 0:
        return RefinedPeaks(lag, value, 0)
    # 1. |F| on the quarter-sample grid over ±1 sample (the integer lags already known)
    offsets = grid_offsets()
    integer = np.isclose(offsets, np.round(offsets))
    at = lag[beams, slots]
    sub = spec.rows(beams)
    grid_values = np.empty((len(beams), len(offsets)), dtype=np.complex128)
    grid_values[:, integer] = values[beams, slots]
    grid_values[:, ~integer] = sub.at(at[:, None] + offsets[None, ~integer])
    # 2. the lobes that may still win, each refined within its own bracket
    ranked, exists = contenders(np.abs(grid_values), straddle_ratio(sub))
    rows, columns = np.nonzero(exists)
    start = at[rows] + offsets[ranked[rows, columns]]
    window = (at[rows] + offsets[0], at[rows] + offsets[-1])
    refined_lag, refined_value, spent = safeguarded_newton(
        sub.rows(rows), start, np.maximum(start - GRID_STEP, window[0]), np.minimum(start + GRID_STEP, window[1]),
        precision, max_steps)
    # 3. the highest refined contender of each peak
    best_lag = np.full(exists.shape, np.nan)
    best_value = np.zeros(exists.shape, dtype=np.complex128)
    best_lag[rows, columns], best_value[rows, columns] = refined_lag, refined_value
    pick = np.argmax(np.abs(best_value), axis=1)[:, None]
    lag[beams, slots] = np.take_along_axis(best_lag, pick, axis=1)[:, 0]
    value[beams, slots] = np.take_along_axis(best_value, pick, axis=1)[:, 0]
    return RefinedPeaks(lag, value, int((~integer).sum()) * len(beams) + spent)
