"""Point targets for the ranging experiments: echo paths at chosen ranges, bearings and per-RE SNRs."""

from __future__ import annotations

import numpy as np

from radioslam.antenna.codebook import BeamSet, nearest_beam_row
from radioslam.capture import Capture, CaptureMode
from radioslam.config import RadioConfig, bistatic_delay_s
from radioslam.sim.noise import noise_variance
from radioslam.sim.paths import EchoPaths, PathKind
from radioslam.sim.simulator import Simulator


def nearest_beam(radio: RadioConfig, bearing_rad: float) -> int:
    """Row of the beam pointing closest to a terminal-frame bearing."""
    return nearest_beam_row(BeamSet.from_config(radio).angle, bearing_rad)


def point_paths(radio: RadioConfig, ranges_m, bearing_rad: float, snr_db, phases_rad=None) -> EchoPaths:
    """Paths whose per-RE SNR on the beam facing ``bearing_rad`` is ``snr_db`` each (no leakage)."""
    ranges_m = np.atleast_1d(np.asarray(ranges_m, dtype=np.float64))
    snr = np.broadcast_to(np.asarray(snr_db, dtype=np.float64), ranges_m.shape)
    beams = BeamSet.from_config(radio)
    gain = beams.two_way_gain(np.array([bearing_rad]))[nearest_beam(radio, bearing_rad), 0]
    sigma2 = noise_variance(radio)
    magnitude = np.sqrt(sigma2 * 10.0 ** (snr / 10.0)) / gain
    phase = np.zeros_like(ranges_m) if phases_rad is None else np.asarray(phases_rad, dtype=np.float64)
    n = len(ranges_m)
    return EchoPaths(
        bistatic_delay_s(ranges_m, radio.array_baseline_m), magnitude * np.exp(1j * phase),
        np.full(n, bearing_rad), np.full(n, PathKind.SPECULAR, dtype=np.int8), np.full(n, -1),
        np.column_stack([ranges_m * np.cos(bearing_rad), ranges_m * np.sin(bearing_rad)]))


def capture_point_targets(radio: RadioConfig, paths: EchoPaths, rows: list[int], rng: np.random.Generator,
                          mode: CaptureMode = CaptureMode.WAVEFORM) -> Capture:
    return Simulator.from_radio(radio, mode, rows=np.asarray(rows)).capture_from_paths(paths, rng)
