"""Simulated calibration of a run's radio: eq. (11) on simulated plates and the leakage of an empty sweep."""

from __future__ import annotations

from pathlib import Path

from radioslam.io import write_calibration
from radioslam.sensing import Receiver, SensingConfig, estimate_hardware_delay
from radioslam.sim.calibration_targets import calibration_ranges, simulate_calibration


def simulated_calibration(radio, seed: int, targets: int | None = None, spacing: float | None = None):
    """eq. (11) on metal plates simulated with this radio, and the leakage of a sweep with nothing in range."""
    ranges = calibration_ranges(radio, targets, spacing)
    captures, empty = simulate_calibration(radio, ranges, seed)
    return estimate_hardware_delay(captures, ranges, source=f"simulated: {len(ranges)} metal plates and an empty "
                                   f"sweep, seed {seed}", empty=empty)


def calibrated_receiver(radio, seed: int, sensing: SensingConfig | None = None) -> Receiver:
    """The receiver a run of this radio senses with: T_H and the leakage from :func:`simulated_calibration`."""
    cal = simulated_calibration(radio, seed)
    return Receiver(radio, cal.hardware_delay_s, sensing, cal.leakage)


def calibrate_simulated(radio, out: Path, seed: int, targets: int | None = None, spacing: float | None = None):
    """:func:`simulated_calibration`, written to ``calibration.json``."""
    cal = simulated_calibration(radio, seed, targets, spacing)
    write_calibration(out, cal)
    return cal
