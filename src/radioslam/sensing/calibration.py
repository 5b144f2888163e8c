"""Hardware delay bias estimation, paper §III-C eq. (11).

N_T targets at known ranges R_k on the array normal: each gives T1 (PSS sync)
and T2 (the refined OFDM offset within the sync grid) on the beam facing it, and

    T_H = (1/N_T) Σ_k (T1⁽ᵏ⁾ + T2⁽ᵏ⁾ − T_O⁽ᵏ⁾),   T_O⁽ᵏ⁾ = 2√(R_k² + b²/4)/c.      (11)

Before T_H is known nothing separates a target from the TX→RX leakage, so the
estimate is made in two passes: (1) the strongest refined peak of every target
gives a robust first guess (the median of T1 + T2 − T_O); (2) each target is then
re-detected in a ±1.5-cell gate around T_H + T_O with the leakage (at T_H + b/c)
estimated and cancelled jointly, and (11) is evaluated on those.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from radioslam.antenna.codebook import nearest_beam_row
from radioslam.capture import Capture
from radioslam.config import bistatic_delay_s
from radioslam.sensing.config import SensingConfig
from radioslam.sensing.errors import SensingError
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

    def to_dict(self) -> dict:
        return {"method": "eq. (11), arXiv 2507.04662", "hardware_delay_s": self.hardware_delay_s,
                "source": self.source,
                "targets": [{"range_m": t.range_m, "t1_s": t.t1_s, "t2_s": t.t2_s, "ota_s": t.ota_s,
                             "bias_s": t.bias_s} for t in self.targets]}


def estimate_hardware_delay(captures: list[Capture], ranges_m: np.ndarray, cfg: SensingConfig | None = None,
                            source: str = "") -> Calibration:
    """Eq. (11) over targets on the array normal, one capture per target."""
    cfg = cfg or SensingConfig()
    ranges_m = np.asarray(ranges_m, dtype=np.float64)
    if len(captures) != len(ranges_m) or len(captures) == 0:
        raise SensingError(f"{len(captures)} captures for {len(ranges_m)} ranges", field="ranges")
    radio = captures[0].radio
    ota = bistatic_delay_s(ranges_m, radio.array_baseline_m)
    half_gate = GATE_CELLS / radio.sample_rate_hz
    rows = [nearest_beam_row(cap.beam_angle_rad, 0.0) for cap in captures]  # the beams facing the targets
    # pass 1: the strongest peak of each target, no gate and no leakage model
    blind = Receiver(radio, None, cfg)
    guess = float(np.median([sum(blind.beam_delay(cap, row)) - t_o for cap, row, t_o in zip(captures, rows, ota)]))
    # pass 2 (twice): gate around T_H + T_O, leakage at T_H + b/c cancelled jointly
    for _ in range(2):
        receiver = Receiver(radio, guess, cfg)
        targets = []
        for cap, row, r, t_o in zip(captures, rows, ranges_m, ota):
            t1, t2 = receiver.beam_delay(cap, row, (guess + t_o - half_gate, guess + t_o + half_gate))
            if not np.isfinite(t2):
                raise SensingError(f"no echo of the calibration target at {r:g} m", file=cap.source,
                                   field=f"target {r:g} m")
            targets.append(CalibrationTarget(float(r), t1, t2, float(t_o)))
        guess = float(np.mean([t.bias_s for t in targets]))  # eq. (11)
    return Calibration(guess, targets, source)
