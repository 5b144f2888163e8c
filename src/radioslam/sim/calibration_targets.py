"""Simulated calibration measurements for eq. (11): a 1 m² metal plate on the array normal at
N_T known ranges (0.8 m, 1.6 m, … by default), as in the paper's §V-A procedure; and a sweep of
every beam with nothing in range, which measures the TX→RX leakage."""

from __future__ import annotations

import numpy as np

from radioslam.capture import Capture, CaptureMode
from radioslam.config import RadioConfig
from radioslam.scene.builtin import single_plate
from radioslam.sim.paths import leakage_paths
from radioslam.sim.simulator import Simulator


def calibration_ranges(radio: RadioConfig, targets: int | None = None, spacing_m: float | None = None) -> np.ndarray:
    n = radio.calibration_targets if targets is None else targets
    step = radio.calibration_spacing_m if spacing_m is None else spacing_m
    return step * np.arange(1, n + 1)


def boresight_row(radio: RadioConfig) -> int:
    """Row of orientation 0, codebook indices i = 0 and j = 0 in the beam sweep (the array normal)."""
    return (radio.elevation_beams - 1) // 2 * radio.azimuth_beams + radio.beams_per_side


def plate_simulator(radio: RadioConfig, range_m: float, mode: CaptureMode = CaptureMode.WAVEFORM,
                    calibrating: bool = False) -> Simulator:
    """The boresight beam of ``radio`` facing the 1 m² metal plate at ``range_m``; ``calibrating``: as the
    hardware was when calibrated, before any hardware-delay drift."""
    impairments = radio.impairments.at_calibration() if calibrating else radio.impairments
    scene = single_plate(float(range_m)).with_radio(**{**radio.model_dump(), "impairments": impairments})
    return Simulator.from_scene(scene, mode, rows=[boresight_row(radio)])


def simulate_calibration_captures(radio: RadioConfig, ranges_m: np.ndarray, seed: int,
                                  mode: CaptureMode = CaptureMode.WAVEFORM) -> list[Capture]:
    """One capture of the boresight beam per plate range; target k draws from child k of ``seed``."""
    children = np.random.SeedSequence(seed).spawn(len(ranges_m))
    captures = []
    for r, child in zip(ranges_m, children):
        simulator = plate_simulator(radio, r, mode, calibrating=True)
        captures.append(simulator.simulate_pose(0, np.random.default_rng(child)))
    return captures


def simulate_empty_capture(radio: RadioConfig, rng: np.random.Generator,
                           mode: CaptureMode = CaptureMode.WAVEFORM) -> Capture:
    """Every beam of ``radio``, as calibrated (no drift yet), with nothing in range: the leakage alone."""
    calibrated = radio.model_copy(update={"impairments": radio.impairments.at_calibration()})
    return Simulator.from_radio(calibrated, mode).capture_from_paths(leakage_paths(calibrated), rng)


def simulate_calibration(radio: RadioConfig, ranges_m: np.ndarray, seed: int,
                         mode: CaptureMode = CaptureMode.WAVEFORM) -> tuple[list[Capture], Capture]:
    """The plates' captures (target k from child k of ``seed``) and the empty sweep (the next child)."""
    captures = simulate_calibration_captures(radio, ranges_m, seed, mode)
    empty_stream = np.random.SeedSequence(seed).spawn(len(ranges_m) + 1)[-1]
    return captures, simulate_empty_capture(radio, np.random.default_rng(empty_stream), mode)
