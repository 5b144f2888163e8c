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
* Multi: CFAR on the residual profile, then successive cancellation: the strongest
  detection is refined, subtracted, and the search repeats; after each new path
  every path found so far is re-estimated with the others cancelled (the cyclic
  RELAX of Li & Stoica 1996), which resolves paths closer than one range cell.
All steps are vectorized over beams.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from radioslam.nr.ofdm import phase_ramp
from radioslam.sensing.bisection import neighbour_values
from radioslam.sensing.cfar import cfar_threshold, noise_threshold
from radioslam.sensing.config import SensingConfig
from radioslam.sensing.profile import RangeSpectrum, signed_lag
from radioslam.sensing.refiner import PeakRefiner

POLISH_STEPS = 4
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

    def mask(self, fft_size: int) -> np.ndarray:
        """(B, N): which integer lags lie in the gate."""
        return self.contains(signed_lag(np.arange(fft_size), fft_size)[None, :])

    def contains(self, lag: np.ndarray) -> np.ndarray:
        return (lag >= self.low[:, None]) & (lag <= self.high[:, None])


def local_maxima(power: np.ndarray) -> np.ndarray:
    return (power > np.roll(power, 1, axis=1)) & (power >= np.roll(power, -1, axis=1))


def strongest(power: np.ndarray, allowed: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """The k largest allowed cells per beam: integer lags (B, k) and whether each exists."""
    masked = np.where(allowed, power, -np.inf)
    # the k largest, unordered; partitioned from the small end of −power: introselect slows ten-fold on
    # the many equal −inf cells when the k-th is sought from the other end
    top = np.argpartition(-masked, k - 1, axis=1)[:, :k]
    order = np.argsort(-np.take_along_axis(masked, top, axis=1), axis=1, kind="stable")
    idx = np.take_along_axis(top, order, axis=1)
    return idx, np.isfinite(np.take_along_axis(masked, idx, axis=1))


def _cancel_all_but(spec: RangeSpectrum, lag: np.ndarray, amp: np.ndarray, j: int) -> RangeSpectrum:
    others = amp.copy()
    others[:, j] = 0.0
    return spec.minus(spec.path_spectrum(np.nan_to_num(lag), others))


def joint_amplitudes(spec: RangeSpectrum, lag: np.ndarray, present: np.ndarray) -> np.ndarray:
    """Least-squares amplitudes (B, M) of paths at given lags, all at once.

    Model S = Σ_k a_k·m·e_k with e_k(p) = e^{−j2πp t_k/N}: the normal equations are
    Σ_j (Σ_p m e_i* e_j) a_j = Σ_p e_i* S (the ML estimate for the MF model m = W).
    Both sides are DFT evaluations: Σ_p m e_i* e_j is the model's kernel at t_i − t_j and
    Σ_p e_i* S is the unnormalized profile at t_i. The model is real, so the Gram matrix is
    Hermitian with Σ_p m on its diagonal: only the pairs i < j are evaluated.
    """
    b, m = lag.shape
    t = np.nan_to_num(lag)
    upper, lower = np.triu_indices(m, 1)
    gram = np.zeros((b, m, m), dtype=np.complex128)
    gram[:, upper, lower] = spec.kernel(t[:, upper] - t[:, lower])
    gram[:, lower, upper] = gram[:, upper, lower].conj()
    gram[:, np.arange(m), np.arange(m)] = spec.scale[:, None]
    gram *= present[:, :, None] & present[:, None, :]
    rhs = spec.at(t) * spec.scale[:, None] * present
    gram = gram + np.eye(m)[None] * (~present)[:, :, None]  # absent paths: a = 0
    return np.linalg.solve(_ridge(gram), rhs[..., None])[..., 0]


def _ridge(gram: np.ndarray) -> np.ndarray:
    """A 1e-9 relative diagonal load, so two paths that met at one lag stay solvable."""
    load = 1e-9 * np.abs(np.trace(gram, axis1=1, axis2=2))[:, None, None] / gram.shape[1]
    return gram + load * np.eye(gram.shape[1])[None]


def relax(spec: RangeSpectrum, lag: np.ndarray, amp: np.ndarray, present: np.ndarray, fixed: np.ndarray,
          passes: int, refiner: PeakRefiner) -> tuple[np.ndarray, np.ndarray, int]:
    """Cyclic re-estimation of paths (B, M) (RELAX): each lag with the others cancelled, then
    all amplitudes jointly by least squares. A ``fixed`` column (the leakage) keeps its lag.
    """
    lag, amp, evaluations = lag.copy(), amp.copy(), 0
    b = lag.shape[0]
    movable = [j for j in np.flatnonzero(present.any(axis=0)) if not fixed[j]]
    for _ in range(passes):
        amp = joint_amplitudes(spec, lag, present)  # the sequential amplitudes are biased by each other
        for j in movable:
            resid = _cancel_all_but(spec, lag, amp, j)
            here = np.flatnonzero(present[:, j])
            refined = refiner.track(resid.rows(here), lag[here, j])
            lag[here, j] = refined.lag[:, 0]
            amp = joint_amplitudes(spec, lag, present)
            evaluations += refined.dft_evaluations + b * lag.shape[1]
    return lag, amp, evaluations


def polish(spec: RangeSpectrum, lag: np.ndarray, present: np.ndarray, fixed: np.ndarray,
           iterations: int) -> tuple[np.ndarray, np.ndarray]:
    """Joint Gauss–Newton refinement of all movable lags (B, M), amplitudes by least squares
    at every step (variable projection, Kaufman's projected Jacobian). Minimizes
    Σ_p |S − Σ_k a_k m e_k|² / m, the ML cost of the model; steps are clipped to ±0.25 sample.
    Converges where cyclic RELAX crawls: paths closer than one range cell (the leakage next
    to a near target, Fig. 8's pair).
    """
    lag = lag.copy()
    movable = present & ~fixed[None, :]
    w = 2j * np.pi * spec.p / spec.fft_size
    eye = np.eye(lag.shape[1])[None]
    model, inv_m = spec.model[:, None, :], 1.0 / spec.model[:, None, :]  # (B, 1, P)
    for _ in range(iterations):  # sums over subcarriers as batched products (B, M, P) @ (B, P, ·)
        e = phase_ramp(np.nan_to_num(lag), spec.p, spec.fft_size) * present[..., None]
        e_conj = e.conj()
        gram = _ridge((e_conj * model) @ e.transpose(0, 2, 1) + eye * (~present)[:, :, None])  # Σ_p e_i* m e_j
        amp = np.linalg.solve(gram, e_conj @ spec.s[..., None])[..., 0]  # :func:`joint_amplitudes`, from e
        resid = spec.s - (amp[:, None, :] @ e)[:, 0] * spec.model  # S − Σ_k a_k m e_k
        d = amp[..., None] * model * e * (-w)  # ∂(model)/∂t_k
        # project out the amplitudes' span (Kaufman's variable-projection Jacobian)
        coef = np.linalg.solve(gram, e_conj @ d.transpose(0, 2, 1))  # (B, M_cols, M_derivs)
        d = d - (coef.transpose(0, 2, 1) @ e) * model
        weighted = d.conj() * inv_m  # d_i* / m
        hess = (weighted @ d.transpose(0, 2, 1)).real
        grad = (weighted @ resid[..., None])[..., 0].real
        hess = hess * movable[:, :, None] * movable[:, None, :] + eye * (~movable)[:, :, None]
        step = np.linalg.solve(_ridge(hess), (grad * movable)[..., None])[..., 0]
        lag = np.where(movable, lag + np.clip(step, -0.25, 0.25), lag)
    return lag, joint_amplitudes(spec, lag, present)


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
    near = close_pairs(lag, present)
    if near.any():
        lag, amp = lag.copy(), amp.copy()
        lag[near], amp[near] = polish(spec.rows(near), lag[near], present[near], fixed, POLISH_STEPS)
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


def residual_floor(spec: RangeSpectrum, leakage: np.ndarray, residual_db: float) -> np.ndarray:
    """(B, N) what cancelling the leakage (its spectrum ``leakage``, (B, n_sc)) may leave at each lag:
    its profile's power, ``residual_db`` below it."""
    floor = np.zeros((leakage.shape[0], spec.fft_size))
    known = np.flatnonzero(np.any(leakage != 0, axis=1))  # beams without a leakage estimate: nothing to leave
    if len(known):
        profile = RangeSpectrum(leakage[known], spec.model[known], spec.p, spec.fft_size).profile()
        floor[known] = 10.0 ** (residual_db / 10.0) * np.abs(profile) ** 2
    return floor


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
    leakage = spec.path_spectrum(np.nan_to_num(lag[:, :1]), amp[:, :1])
    resid = spec.minus(leakage)
    profile = resid.profile()
    power = np.abs(profile) ** 2
    n = spec.fft_size
    floor = noise_threshold(power, cfg.noise_pfa) + residual_floor(spec, leakage, cfg.leakage_residual_db)
    peaks, ok = strongest(power, local_maxima(power) & gate.mask(n) & (power > floor), cfg.peaks)
    active = ok
    if contenders_db is not None:
        peak_power = np.take_along_axis(power, peaks, axis=1)
        active = ok & (peak_power >= peak_power[:, :1] * 10 ** (-contenders_db / 10))
    refined = refiner.refine(resid, signed_lag(peaks, n), neighbour_values(profile, peaks), active)
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
    """CFAR + successive cancellation with RELAX re-estimation (paper §III-B)."""
    m = cfg.max_targets
    lag, amp, present, fixed = _with_leakage(spec, gate, m)
    n, rows = spec.fft_size, np.arange(spec.s.shape[0])
    allowed_lags = gate.mask(n)
    leakage_floor = residual_floor(spec, spec.path_spectrum(np.nan_to_num(lag[:, :1]), amp[:, :1]),
                                   cfg.leakage_residual_db)
    searching = np.ones(len(rows), dtype=bool)
    spent = 0
    for slot in range(1, m + 1):
        # only the beams still searching: a beam whose last search found nothing is done, its paths refined
        active = np.flatnonzero(searching)
        sub = spec.rows(active)
        resid = sub.minus(sub.path_spectrum(np.nan_to_num(lag[active]), np.where(present[active], amp[active], 0.0)))
        profile = resid.profile()
        power = np.abs(profile) ** 2
        # CFAR only where it can matter: the local maxima in the gate above the noise threshold
        floor = noise_threshold(power, cfg.noise_pfa) + leakage_floor[active]
        candidate = local_maxima(power) & allowed_lags[active] & (power > floor)
        cells = np.nonzero(candidate)
        candidate[cells] = power[cells] > cfar_threshold(power, cfg.cfar, cfg.cfar_guard, cfg.cfar_train,
                                                         cfg.cfar_pfa, cells)
        peaks, ok = strongest(power, candidate, 1)
        found = ok[:, 0]
        searching[active] = found
        if not found.any():
            break
        now = active[found]
        refined = refiner.refine(resid.rows(found), signed_lag(peaks[found], n), neighbour_values(profile[found],
                                                                                                peaks[found]))
        present[now, slot] = True
        lag[now, slot], amp[now, slot] = refined.lag[:, 0], refined.amplitude[:, 0]
        held = slice(0, 1 + slot)
        lag[now, held], amp[now, held], used = refine_jointly(spec.rows(now), lag[now, held], amp[now, held],
                                                              present[now, held], fixed[held], cfg.relax_passes,
                                                              refiner)
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
        amp[merged] = joint_amplitudes(spec.rows(merged), lag[merged], present[merged])
    valid = present[:, 1:] & gate.contains(np.nan_to_num(lag[:, 1:], nan=-np.inf))
    return Detections(lag[:, 1:], amp[:, 1:], valid, spent)
