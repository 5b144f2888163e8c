"""Target detection on range profiles (paper §III-A single target, §III-B multiple targets).

* Gate: only lags whose range lies in [min_range, max_range] after the calibrated
  hardware delay can be targets, so the TX→RX leakage at range ≈ 0 never is.
* Leakage cancellation: the leakage sits at a known lag (calibrated T_H plus its own
  calibrated delay, :mod:`radioslam.sensing.leakage`, or b/c); its amplitude is estimated
  there, jointly with the targets, and subtracted before the search, so its range
  sidelobes are not reported either; what a slightly wrong lag would leave joins the
  detection threshold (``leakage_residual_db`` below the leakage's own profile).
* Single (the paper's): the K̂ largest local maxima in the gate that clear the noise
  floor are refined (T2, :mod:`radioslam.sensing.refiner`); the strongest is the beam's target.
* Single: the target is then re-estimated with the leakage cancelled (a cyclic RELAX pass,
  Li & Stoica 1996), and jointly with it by Gauss–Newton where the two lie within
  ``NEAR_CELLS`` (:mod:`radioslam.sensing.joint`).
* Multi: CFAR on the residual profile, then successive cancellation: the strongest
  detection is refined with the paths found so far cancelled in the lag domain
  (:mod:`radioslam.sensing.cancelled`), and all of them are re-estimated jointly, the
  ML estimate by variable-projection Gauss–Newton (:mod:`radioslam.sensing.joint`),
  which also resolves paths closer than one range cell; then the search repeats.
All steps are vectorized over beams.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from radioslam.sensing.bisection import neighbour_values
from radioslam.sensing.cancelled import CancelledSpectrum
from radioslam.sensing.cfar import cfar_threshold, noise_threshold
from radioslam.sensing.config import SensingConfig
from radioslam.sensing.joint import joint_amplitudes, refine_paths
from radioslam.sensing.profile import RangeSpectrum, signed_lag
from radioslam.sensing.refiner import PeakRefiner

JOINT_STEPS = 4  # joint Gauss–Newton steps at most, ±¼ sample each: a path travels at most one sample
NEAR_CELLS = 3.0
MERGE_CELLS = 0.3
# a lone path half a sample off the integer grid loses 2.3 dB (the Dirichlet kernel of
# 792 of 1024 subcarriers); a peak more than twice that below the strongest cannot win
CONTENDER_DB = 6.0


@dataclass(frozen=True)
class Detections:
    """Up to M targets per beam: lags (B, M) after the window offset, amplitudes, validity."""

    lag: np.ndarray
    amplitude: np.ndarray
    valid: np.ndarray
    dft_evaluations: int


@dataclass(frozen=True)
class LagGate:
    """Per beam (B,): the lag interval that holds targets, and the leakage's lag (NaN: none)."""

    low: np.ndarray
    high: np.ndarray
    leakage: np.ndarray

    def contains(self, lag: np.ndarray) -> np.ndarray:
        return (lag >= self.low[:, None]) & (lag <= self.high[:, None])

    def window(self, fft_size: int) -> "GateWindow":
        """The integer lags that any beam's gate holds (a few dozen of the N: 40 m is 33 samples)."""
        low, high = int(np.floor(np.nanmin(self.low))), int(np.ceil(np.nanmax(self.high)))
        lags = np.arange(low - 1, min(high, low + fft_size - 1) + 2)  # each column once, a neighbour either side
        inner = lags[1:-1]
        return GateWindow(lags % fft_size, inner.astype(np.float64),
                          self.contains(signed_lag(inner, fft_size)[None, :]))


@dataclass(frozen=True)
class GateWindow:
    """The FFT columns (C + 2,) of the lags lo − 1 … hi + 1 around every beam's gate, the inner C lags
    (consecutive), and which of them each beam's gate holds (B, C): peaks are searched there only,
    the rest of the profile serves the noise floor and the CFAR training cells."""

    columns: np.ndarray
    lags: np.ndarray
    allowed: np.ndarray

    @property
    def inner(self) -> np.ndarray:
        return self.columns[1:-1]

    def rows(self, rows: np.ndarray) -> "GateWindow":
        return GateWindow(self.columns, self.lags, self.allowed[rows])

    def maxima(self, power: np.ndarray, floor: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Of a profile's power (B, N): the gated local maxima above ``floor`` (B, C), and the power there
        (B, C)."""
        around = power[:, self.columns]
        here = around[:, 1:-1]
        return (here > around[:, :-2]) & (here >= around[:, 2:]) & self.allowed & (here > floor), here


def strongest(power: np.ndarray, allowed: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """The k largest allowed cells per beam, strongest first: their indices (B, k) and whether each exists."""
    masked = np.where(allowed, power, -np.inf)
    rows = np.arange(len(power))
    idx = np.empty((len(power), k), dtype=np.int64)
    exists = np.empty((len(power), k), dtype=bool)
    for j in range(k):  # k argmax passes (k ≤ 16): a partition slows ten-fold on the many equal −inf cells
        idx[:, j] = np.argmax(masked, axis=1)
        exists[:, j] = np.isfinite(masked[rows, idx[:, j]])
        masked[rows, idx[:, j]] = -np.inf
    return idx, exists


def relax(spec: RangeSpectrum, lag: np.ndarray, amp: np.ndarray, present: np.ndarray, fixed: np.ndarray,
          passes: int, refiner: PeakRefiner) -> tuple[np.ndarray, np.ndarray, int]:
    """Cyclic re-estimation of paths (B, M) (RELAX): each lag with the others cancelled, then
    all amplitudes jointly by least squares. A ``fixed`` column (the leakage) keeps its lag.
    """
    lag, amp, evaluations = lag.copy(), amp.copy(), 0
    b = lag.shape[0]
    rows = np.arange(b)
    movable = [j for j in np.flatnonzero(present.any(axis=0)) if not fixed[j]]
    for _ in range(passes):
        amp = joint_amplitudes(spec, rows, lag, present)  # the sequential amplitudes are biased by each other
        for j in movable:
            here = np.flatnonzero(present[:, j])
            others = amp[here].copy()
            others[:, j] = 0.0
            refined = refiner.track(CancelledSpectrum(spec, rows[here], lag[here], others), lag[here, j])
            lag[here, j] = refined.lag[:, 0]
            amp = joint_amplitudes(spec, rows, lag, present)
            evaluations += refined.dft_evaluations + b * lag.shape[1]
    return lag, amp, evaluations


def close_pairs(lag: np.ndarray, present: np.ndarray, cells: float = NEAR_CELLS) -> np.ndarray:
    """Beams (B,) with two present paths closer than ``cells``: only these need joint estimation."""
    gap = np.abs(lag[:, :, None] - lag[:, None, :])
    both = present[:, :, None] & present[:, None, :] & ~np.eye(lag.shape[1], dtype=bool)[None]
    return (both & (gap < cells)).any(axis=(1, 2))


def refine_jointly(spec: RangeSpectrum, lag: np.ndarray, amp: np.ndarray, present: np.ndarray,
                   fixed: np.ndarray, passes: int, refiner: PeakRefiner) -> tuple[np.ndarray, np.ndarray, int]:
    """RELAX passes on every beam, then the joint polish where paths are within ``NEAR_CELLS``.

    Farther apart the cyclic estimates have converged after a pass (a path's range
    sidelobes at another are below −20 dB); closer, RELAX crawls and Gauss–Newton finishes.
    """
    lag, amp, spent = relax(spec, lag, amp, present, fixed, passes, refiner)
    near = np.flatnonzero(close_pairs(lag, present))
    if len(near):
        lag, amp = lag.copy(), amp.copy()
        lag[near], amp[near], used = refine_paths(spec, near, lag[near], present[near], fixed, refiner.precision,
                                                  JOINT_STEPS)
        spent += used
    return lag, amp, spent


def _with_leakage(spec: RangeSpectrum, gate: LagGate, slots: int):
    """Path tables (B, 1 + slots) whose column 0 is the leakage, estimated at its known lag."""
    b = spec.s.shape[0]
    lag = np.full((b, 1 + slots), np.nan)
    amp = np.zeros((b, 1 + slots), dtype=np.complex128)
    present = np.zeros((b, 1 + slots), dtype=bool)
    present[:, 0] = np.isfinite(gate.leakage)
    lag[:, 0] = gate.leakage
    amp[:, 0] = np.where(present[:, 0], spec.at(np.nan_to_num(gate.leakage)[:, None])[:, 0], 0.0)
    fixed = np.zeros(1 + slots, dtype=bool)
    fixed[0] = True
    return lag, amp, present, fixed


def leakage_floor(spec: RangeSpectrum, window: GateWindow, lag: np.ndarray, amp: np.ndarray,
                  residual_db: float) -> np.ndarray:
    """(B, C) what cancelling the leakage (lag and amplitude (B,), 0: none) may leave at the window's lags:
    its profile's power there, |a·K(t − t_L)/Σm|², ``residual_db`` below it."""
    start = window.lags[0] - np.nan_to_num(lag)  # the window's lags are consecutive
    response = amp[:, None] * spec.kernel_run(start, len(window.lags)) / spec.scale[:, None]
    return 10.0 ** (residual_db / 10.0) * np.abs(response) ** 2


def leakage_cancelled(spec: RangeSpectrum, gate: LagGate) -> RangeSpectrum:
    """The spectrum with the leakage, estimated at its known lag, subtracted: what :func:`pdp_peaks`
    searches."""
    lag, amp, _, _ = _with_leakage(spec, gate, 0)
    return spec.minus(spec.path_spectrum(np.nan_to_num(lag), amp))


def pdp_peaks(spec: RangeSpectrum, gate: LagGate, cfg: SensingConfig, refiner: PeakRefiner,
              contenders_db: float | None = None):
    """Leakage estimated and cancelled, then the K̂ largest local maxima in the gate that clear
    the noise floor, each refined by ``refiner``. Returns (paths, refined peaks (B, K̂), exist (B, K̂)).

    With ``contenders_db``, only peaks within that many dB of the beam's strongest integer
    peak are refined (the others keep their integer lag): enough when only the strongest
    refined peak is wanted, since refinement recovers at most the straddle loss.
    """
    lag, amp, present, fixed = _with_leakage(spec, gate, 1)
    profile = spec.minus(spec.path_spectrum(np.nan_to_num(lag[:, :1]), amp[:, :1])).profile()
    power = np.abs(profile) ** 2
    n = spec.fft_size
    window = gate.window(n)
    floor = noise_threshold(power, cfg.noise_pfa) + leakage_floor(spec, window, lag[:, 0], amp[:, 0],
                                                                  cfg.leakage_residual_db)
    candidate, gated_power = window.maxima(power, floor)
    cells, ok = strongest(gated_power, candidate, cfg.peaks)
    peaks = window.inner[cells]
    active = ok
    if contenders_db is not None:
        peak_power = np.take_along_axis(gated_power, cells, axis=1)
        active = ok & (peak_power >= peak_power[:, :1] * 10 ** (-contenders_db / 10))
    cancelled = CancelledSpectrum(spec, np.arange(spec.beam_count), lag[:, :1], amp[:, :1])
    refined = refiner.refine(cancelled, signed_lag(peaks, n), neighbour_values(profile, peaks), active)
    return (lag, amp, present, fixed), refined, ok


def detect_single(spec: RangeSpectrum, gate: LagGate, cfg: SensingConfig, refiner: PeakRefiner) -> Detections:
    """The strongest refined peak per beam in the gate (paper §III-A), leakage cancelled jointly."""
    (lag, amp, present, fixed), refined, ok = pdp_peaks(spec, gate, cfg, refiner, CONTENDER_DB)
    score = np.where(ok, np.abs(refined.amplitude), -1.0)
    best = np.argmax(score, axis=1)
    rows = np.arange(len(best))
    present[:, 1] = ok[rows, best]
    lag[:, 1] = refined.lag[rows, best]
    amp[:, 1] = np.where(present[:, 1], refined.amplitude[rows, best], 0.0)
    lag, amp, spent = refine_jointly(spec, lag, amp, present, fixed, cfg.relax_passes, refiner)
    valid = present[:, 1:] & gate.contains(lag[:, 1:])
    return Detections(lag[:, 1:], amp[:, 1:], valid, refined.dft_evaluations + spent)


def detect_multi(spec: RangeSpectrum, gate: LagGate, cfg: SensingConfig, refiner: PeakRefiner) -> Detections:
    """CFAR + successive cancellation with joint re-estimation of every path found (paper §III-B)."""
    m = cfg.max_targets
    lag, amp, present, fixed = _with_leakage(spec, gate, m)
    n, rows = spec.fft_size, np.arange(spec.s.shape[0])
    window = gate.window(n)
    floor_of_leakage = leakage_floor(spec, window, lag[:, 0], amp[:, 0], cfg.leakage_residual_db)
    searching = np.ones(len(rows), dtype=bool)
    spent = 0
    for slot in range(1, m + 1):
        # only the beams still searching: a beam whose last search found nothing is done, its paths refined
        active = np.flatnonzero(searching)
        sub = spec if len(active) == len(rows) else spec.rows(active)
        known = slice(0, slot)  # the leakage and the paths found so far (the later columns are empty)
        resid = sub.minus(sub.path_spectrum(np.nan_to_num(lag[active, known]),
                                            np.where(present[active, known], amp[active, known], 0.0)))
        profile = resid.profile()
        power = np.abs(profile) ** 2
        # CFAR only where it can matter: the local maxima in the gate above the noise threshold
        floor = noise_threshold(power, cfg.noise_pfa) + floor_of_leakage[active]
        candidate, gated_power = window.rows(active).maxima(power, floor)
        cells = np.nonzero(candidate)
        candidate[cells] = gated_power[cells] > cfar_threshold(power, cfg.cfar, cfg.cfar_guard, cfg.cfar_train,
                                                               cfg.cfar_pfa, (cells[0], window.inner[cells[1]]))
        best, ok = strongest(gated_power, candidate, 1)
        peaks = window.inner[best]
        found = ok[:, 0]
        searching[active] = found
        if not found.any():
            break
        now = active[found]
        cancelled = CancelledSpectrum(spec, now, lag[now, known], amp[now, known])  # while the new path is refined
        refined = refiner.refine(cancelled, signed_lag(peaks[found], n), neighbour_values(profile[found], peaks[found]))
        present[now, slot] = True
        lag[now, slot], amp[now, slot] = refined.lag[:, 0], refined.amplitude[:, 0]
        held = slice(0, 1 + slot)
        lag[now, held], amp[now, held], used = refine_paths(spec, now, lag[now, held], present[now, held],
                                                            fixed[held], refiner.precision, JOINT_STEPS)
        spent += refined.dft_evaluations + used
    # two paths that converged onto one another are one target: keep the stronger, and estimate the
    # amplitudes again without the other (two paths at one lag make the least squares ill-posed: their
    # amplitudes grow large and opposite, and the scan's peak, which every point is normalized by, with them)
    gap = np.abs(lag[:, 1:, None] - lag[:, None, 1:])
    weaker = np.abs(amp[:, 1:, None]) < np.abs(amp[:, None, 1:])
    twin = present[:, 1:] & ((gap < MERGE_CELLS) & weaker & present[:, None, 1:]).any(axis=2)
    merged = np.flatnonzero(twin.any(axis=1))
    if len(merged):
        present[:, 1:] &= ~twin
        amp[merged] = joint_amplitudes(spec, merged, lag[merged], present[merged])
    valid = present[:, 1:] & gate.contains(np.nan_to_num(lag[:, 1:], nan=-np.inf))
    return Detections(lag[:, 1:], amp[:, 1:], valid, spent)
