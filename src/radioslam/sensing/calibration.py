"""Hardware delay bias estimation, paper §III-C eq. (11).

N_T targets at known ranges R_k on the array normal: each gives T1 (PSS sync)
and T2 (the refined OFDM offset within the sync grid) on the beam facing it, and

    T_H = (1/N_T) Σ_k (T1⁽ᵏ⁾ + T2⁽ᵏ⁾ − T_O⁽ᵏ⁾),   T_O⁽ᵏ⁾ = 2√(R_k² + b²/4)/c.      (11)

Before T_H is known nothing in one capture separates a target from the TX→RX leakage,
so the estimate is made in two passes: (1) the K̂ strongest refined peaks of every
target each propose T1 + T2 − T_O; the targets' echoes agree on one value, the
leakage (which does not move with the target) proposes a different one for each,
so the value most targets agree on is the first guess; (2) each target is then
re-detected in a ±1.5-cell gate around T_H + T_O with the leakage (at T_H + b/c)
estimated and cancelled jointly, and (11) is evaluated on those.

With a capture of every beam with nothing in range, the leakage is measured first
(:func:`measure_leakage`: its absolute delay and amplitude per beam), cancelled at that
delay in pass 2, and stored relative to T_H (:class:`~radioslam.sensing.leakage.LeakageModel`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from radioslam.antenna.codebook import nearest_beam_row
from radioslam.capture import Capture
from radioslam.config import SPEED_OF_LIGHT, bistatic_delay_s
from radioslam.sensing.config import SensingConfig
from radioslam.sensing.detect import detect_single
from radioslam.sensing.errors import SensingError
from radioslam.sensing.leakage import LeakageModel
from radioslam.sensing.profile import pdp_spectrum
from radioslam.sensing.receiver import Receiver

GATE_CELLS = 1.5


@dataclass(frozen=True)
class CalibrationTarget:
    range_m: float
    t1_s: float
    t2_s: float
    ota_s: float

    @property
    def bias_s(self) -> float:
        """T1 + T2 − T_O of this target (its term of eq. (11))."""
        return self.t1_s + self.t2_s - self.ota_s


@dataclass(frozen=True)
class Calibration:
    """The hardware delay estimate and the targets it came from."""

    hardware_delay_s: float
    targets: list[CalibrationTarget] = field(default_factory=list)
    source: str = ""
    leakage: LeakageModel | None = None

    def to_dict(self) -> dict:
        doc = {"method": "eq. (11), arXiv 2507.04662", "hardware_delay_s": self.hardware_delay_s,
               "source": self.source,
               "targets": [{"range_m": t.range_m, "t1_s": t.t1_s, "t2_s": t.t2_s, "ota_s": t.ota_s,
                            "bias_s": t.bias_s} for t in self.targets]}
        if self.leakage is not None:
            doc["leakage"] = self.leakage.to_dict()
        return doc


def measure_leakage(capture: Capture, cfg: SensingConfig | None = None) -> LeakageModel:
    """The leakage of every beam of a capture with nothing in range, before T_H is known: each beam's
    strongest echo anywhere in the FFT window, refined. ``delay_s`` is absolute (T1 + T2) here. A beam
    whose leakage is too weak to find (the codebook's edge, at a low SNR) gets the others' median delay
    and amplitude 0: the receiver still fits whatever is there at that lag."""
    receiver = Receiver(capture.radio, None, cfg)
    _, _, est = receiver.front_end(capture)  # where a beam's PSS is too weak, its window is the others'
    offset = est.window_offset
    det = detect_single(pdp_spectrum(est, receiver.p, receiver.n), receiver.window_gate(capture, offset),
                        receiver.cfg, receiver.refiner)
    seen = det.valid[:, 0]
    if not seen.any():
        raise SensingError("no leakage on any beam: is the receiver on?", file=capture.source,
                           field="leakage capture")
    delay = (offset + det.lag[:, 0]) / receiver.fs
    return LeakageModel(capture.orientation.copy(), capture.beam_index.copy(),
                        np.where(seen, delay, np.median(delay[seen])), np.where(seen, det.amplitude[:, 0], 0.0),
                        capture.elevation_index.copy())


def estimate_hardware_delay(captures: list[Capture], ranges_m: np.ndarray, cfg: SensingConfig | None = None,
                            source: str = "", empty: Capture | None = None) -> Calibration:
    """Eq. (11) over targets on the array normal, one capture per target; with ``empty``, a capture of
    every beam with nothing in range, the leakage measured first and calibrated too."""
    cfg = cfg or SensingConfig()
    ranges_m = np.asarray(ranges_m, dtype=np.float64)
    if len(captures) != len(ranges_m) or len(captures) == 0:
        raise SensingError(f"{len(captures)} captures for {len(ranges_m)} ranges", field="ranges")
    radio = captures[0].radio
    ota = bistatic_delay_s(ranges_m, radio.array_baseline_m)
    half_gate = GATE_CELLS / radio.sample_rate_hz
    rows = [nearest_beam_row(cap.beam_angle_rad, 0.0) for cap in captures]  # the beams facing the targets
    leakage = None if empty is None else measure_leakage(empty, cfg)  # absolute delays, T_H included
    # pass 1: the value of T1 + T2 − T_O most targets' peaks agree on (the leakage cancelled where measured,
    # T_H first taken where the leakage puts it: b/c before its median delay, where unfound beams' windows go)
    first = None if leakage is None else float(np.median(leakage.delay_s)) - radio.array_baseline_m / SPEED_OF_LIGHT
    blind = Receiver(radio, first, cfg, None if leakage is None else _after(leakage, first))
    guess = consensus([blind.beam_peaks(cap, row) - t_o for cap, row, t_o in zip(captures, rows, ota)],
                      0.5 / radio.sample_rate_hz)
    # pass 2 (twice): gate around T_H + T_O, leakage (at its measured delay, or T_H + b/c) cancelled jointly
    for _ in range(2):
        receiver = Receiver(radio, guess, cfg, _after(leakage, guess))
        targets = []
        for cap, row, r, t_o in zip(captures, rows, ranges_m, ota):
            t1, t2 = receiver.beam_delay(cap, row, (guess + t_o - half_gate, guess + t_o + half_gate))
            if not np.isfinite(t2):
                raise SensingError(f"no echo of the calibration target at {r:g} m", file=cap.source,
                                   field=f"target {r:g} m")
            targets.append(CalibrationTarget(float(r), t1, t2, float(t_o)))
        guess = float(np.mean([t.bias_s for t in targets]))  # eq. (11)
    return Calibration(guess, targets, source, _after(leakage, guess))


def consensus(proposals: list[np.ndarray], tolerance: float) -> float:
    """The value most of the proposal sets (one per target, NaN: none) have a member within
    ``tolerance`` of: the median, over those sets, of each one's nearest member (ties: the
    tighter cluster)."""
    sets = [p[np.isfinite(p)] for p in proposals]
    candidates = np.concatenate(sets) if any(len(p) for p in sets) else np.zeros(0)
    if len(candidates) == 0:
        raise SensingError("no echo on any calibration target", field="targets")
    nearest = np.array([[np.min(np.abs(p - c)) if len(p) else np.inf for p in sets] for c in candidates])
    support = (nearest <= tolerance).sum(axis=1)
    spread = np.where(nearest <= tolerance, nearest, 0.0).sum(axis=1)
    best = np.lexsort((spread, -support))[0]
    agreeing = [p[np.argmin(np.abs(p - candidates[best]))] for p in sets if len(p)
                and np.min(np.abs(p - candidates[best])) <= tolerance]
    return float(np.median(agreeing))


def _after(leakage: LeakageModel | None, hardware_delay_s: float) -> LeakageModel | None:
    """The measured leakage with its delays made relative to T_H."""
    if leakage is None:
        return None
    return LeakageModel(leakage.orientation, leakage.beam_index, leakage.delay_s - hardware_delay_s, leakage.amplitude,
                        leakage.elevation_index)
