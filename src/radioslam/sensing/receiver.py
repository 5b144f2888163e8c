"""The sensing receiver: one capture (IQ or resource grid) → detections → point cloud.

It works on a :class:`~radioslam.capture.Capture` exactly as it would on a
recording from hardware and never sees the scene: the hardware delay comes from
calibration (eq. (11)), not from the radio configuration. Main loop per capture,
one step per comment (paper §III, §IV-A).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from radioslam.capture import Capture, CaptureMode
from radioslam.config import SPEED_OF_LIGHT, RadioConfig, bistatic_delay_s
from radioslam.nr.numerology import Numerology
from radioslam.sensing.config import FAR_GATE_M, NEAR_GATE_M, Detector, PointFilter, SensingConfig
from radioslam.sensing.detect import Detections, LagGate, detect_multi, detect_single, leakage_cancelled, pdp_peaks
from radioslam.sensing.elevation import detection_elevations
from radioslam.sensing.errors import SensingError
from radioslam.sensing.estimate import ChannelEstimate, estimate_channel
from radioslam.sensing.leakage import LeakageModel
from radioslam.sensing.pointcloud import Scan, build_scan
from radioslam.sensing.profile import RangeSpectrum, mf_spectrum, pdp_spectrum, signed_lag
from radioslam.sensing.refiner import PeakRefiner
from radioslam.sensing.sync import coarse_sync

# the radio parameters the receiver's processing depends on
RECEIVER_FIELDS = ("fft_size", "n_subcarriers", "subcarrier_spacing_hz", "symbols_per_frame", "frames", "pss",
                   "n_id2", "array_baseline_m")


@dataclass(frozen=True)
class SensingResult:
    """Everything one capture gave: the scan and the per-beam intermediate results."""

    scan: Scan
    t1_s: np.ndarray  # (B,) PSS synchronization delay
    delay_s: np.ndarray  # (B, M) T1 + T2 of each detection (hardware delay included)
    range_m: np.ndarray  # (B, M)
    power: np.ndarray  # (B, M) |amplitude|²
    valid: np.ndarray  # (B, M)
    dft_evaluations: int
    spectrum: RangeSpectrum  # what the range profiles are computed from, only when asked for
    window_offset: np.ndarray  # (B,)
    receiver: "Receiver"

    @property
    def profile_power(self) -> np.ndarray:
        """(B, N) |F|² at integer lags (leakage included)."""
        return np.abs(self.spectrum.profile()) ** 2

    @property
    def profile_range_m(self) -> np.ndarray:
        """(B, N) range of each integer lag."""
        lags = signed_lag(np.arange(self.spectrum.fft_size), self.spectrum.fft_size)
        return self.receiver.to_range((self.window_offset[:, None] + lags[None, :]) / self.receiver.fs)


class Receiver:
    """Built from the radio, the calibrated hardware delay (None: not yet known), settings and the
    calibrated leakage (None: assumed at b/c after the hardware delay)."""

    def __init__(self, radio: RadioConfig, hardware_delay_s: float | None, cfg: SensingConfig | None = None,
                 leakage: LeakageModel | None = None):
        self.radio, self.hardware_delay_s, self.cfg = radio, hardware_delay_s, cfg or SensingConfig()
        self.leakage = leakage
        num = Numerology.from_config(radio)
        self.fs, self.n, self.p = num.sample_rate_hz, num.fft_size, num.subcarrier_indices()
        self.cell_m = SPEED_OF_LIGHT / (2.0 * self.fs)  # 1.22 m per sample
        self.refiner = PeakRefiner.from_config(self.cfg, self.cell_m)
        self.backoff = int(num.cp_lengths(np.arange(1, 14)).min()) // 2  # FFT window this early

    def _check(self, capture: Capture) -> None:
        for name in RECEIVER_FIELDS:
            if getattr(capture.radio, name) != getattr(self.radio, name):
                raise SensingError(f"{getattr(capture.radio, name)} differs from the receiver's "
                                   f"{getattr(self.radio, name)}", file=capture.source, field=f"radio.{name}")

    def spectrum(self, est: ChannelEstimate) -> RangeSpectrum:
        build = mf_spectrum if self.cfg.detector is Detector.MULTI else pdp_spectrum
        return build(est, self.p, self.n, self.cfg.taper)

    def front_end(self, capture: Capture) -> tuple[np.ndarray, np.ndarray, ChannelEstimate]:
        """T1 (B,) samples, whether sync was found, and the channel estimate."""
        self._check(capture)
        # 1. coarse synchronization on the PSS at f_s/4 (T1); where it is not found, the window goes where
        #    the leakage is (T_H, once calibrated) or where the other beams found theirs
        sync = coarse_sync(capture, self.cfg.decimation, self.cfg.noise_pfa)
        t1 = np.where(sync.found, sync.t1_samples, self._t1_fallback(sync))
        # 2. FFT windows inside every echo's cyclic prefix; LS channel estimate combined over R symbols
        grid = capture.mode is CaptureMode.GRID
        offset = t1 if grid else t1 - self.backoff
        return t1, sync.found, estimate_channel(capture, offset)

    def _t1_fallback(self, sync) -> int:
        if self.hardware_delay_s is not None:
            return int(round(self.hardware_delay_s * self.fs))
        if sync.found.any():
            return int(np.median(sync.t1_samples[sync.found]))
        return 0

    def leakage_delay_s(self, capture: Capture) -> np.ndarray:
        """(B,) the leakage's delay after T_H on each beam: calibrated, or b/c."""
        if self.leakage is None:
            return np.full(len(capture.beam_index), self.radio.array_baseline_m / SPEED_OF_LIGHT)
        return self.leakage.delay_s[self.leakage.rows_of(capture.orientation, capture.beam_index, capture.source,
                                                         capture.elevation_index)]

    def gate(self, capture: Capture, offset: np.ndarray, low_s: np.ndarray, high_s: np.ndarray) -> LagGate:
        leak = (np.full(len(offset), np.nan) if self.hardware_delay_s is None else
                (self.hardware_delay_s + self.leakage_delay_s(capture)) * self.fs - offset)
        return LagGate(low_s * self.fs - offset, high_s * self.fs - offset, leak)

    def window_gate(self, capture: Capture, offset: np.ndarray) -> LagGate:
        """Every lag of each beam's FFT window (N/2 either side of its offset)."""
        return self.gate(capture, offset, (offset - self.n / 2) / self.fs, (offset + self.n / 2) / self.fs)

    @property
    def min_range_m(self) -> float:
        if self.cfg.min_range_m is not None:
            return self.cfg.min_range_m
        return FAR_GATE_M if self.leakage is None else NEAR_GATE_M

    def range_gate(self, capture: Capture, offset: np.ndarray) -> LagGate:
        """Lags of ranges in [min_range, max_range] after the calibrated hardware delay."""
        far = self.cfg.max_range_m or self.radio.max_range_m
        t_lo, t_hi = (self.hardware_delay_s + bistatic_delay_s(np.array([self.min_range_m, far]),
                                                                self.radio.array_baseline_m))
        return self.gate(capture, offset, np.full(len(offset), t_lo), np.full(len(offset), t_hi))

    def detect(self, spec: RangeSpectrum, gate: LagGate) -> Detections:
        run = detect_multi if self.cfg.detector is Detector.MULTI else detect_single
        return run(spec, gate, self.cfg, self.refiner)

    def point_threshold_db(self) -> float:
        if self.cfg.point_threshold_db is not None:
            return self.cfg.point_threshold_db
        return self.cfg.multi_threshold_db if self.cfg.detector is Detector.MULTI else self.radio.point_threshold_db

    def point_floor_db(self) -> float | None:
        """The same-range rule's floor, or None for the paper's scan-peak rule (always for multi)."""
        same_range = self.cfg.detector is Detector.SINGLE and self.cfg.point_filter is PointFilter.SAME_RANGE
        return self.cfg.point_floor_db if same_range else None

    def directions(self, capture: Capture, spec: RangeSpectrum, gate: LagGate, window_offset: np.ndarray,
                   lag: np.ndarray, valid: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Terminal-frame azimuth and elevation of each detection, and the detections a point keeps: for a
        flat scan its beam's (B,), all; with elevation rows (B, M), u_z between the rows' leakage-cancelled
        profiles (:mod:`radioslam.sensing.elevation`), u_y the beam's, the azimuth on the cone they give,
        and only the detections of the row nearest their u_z."""
        if not np.any(capture.elevation_index != 0):
            return capture.beam_angle_rad, capture.beam_elevation_rad, valid
        radio = self.radio
        u_z, nearest = detection_elevations(leakage_cancelled(spec, gate), window_offset, lag, valid,
                                            capture.orientation, capture.beam_index, capture.elevation_index,
                                            radio.array_elements, radio.codebook_bits)
        u_y = np.broadcast_to((2.0 * capture.beam_index / 2**radio.codebook_bits)[:, None], u_z.shape)
        u_z = np.clip(np.nan_to_num(u_z), -np.sqrt(1 - u_y**2) + 1e-9, np.sqrt(1 - u_y**2) - 1e-9)
        normal = capture.orientation * (2 * np.pi / radio.orientations)
        azimuth = normal[:, None] + np.arctan2(u_y, np.sqrt(1.0 - u_y**2 - u_z**2))
        return np.angle(np.exp(1j * azimuth)), np.arcsin(u_z), nearest

    def to_range(self, delay_s: np.ndarray) -> np.ndarray:
        """Range from T1 + T2 after the calibrated hardware delay (bistatic, eq. (11)'s T_O inverted)."""
        half_path = 0.5 * SPEED_OF_LIGHT * (delay_s - self.hardware_delay_s)
        return np.sqrt(np.maximum(half_path**2 - 0.25 * self.radio.array_baseline_m**2, 0.0))

    def sense(self, capture: Capture) -> SensingResult:
        if self.hardware_delay_s is None:
            raise SensingError("no hardware delay: run 'radioslam calibrate' first", field="calibration")
        t1, found, est = self.front_end(capture)
        # 3. range profile: PDP of Ĥ (single target) or MF with coherent integration (multi)
        spec = self.spectrum(est)
        # 4. detection in the range gate, leakage cancelled, peaks refined (T2: bracketed, or the paper's bisection)
        gate = self.range_gate(capture, est.window_offset)
        det = self.detect(spec, gate)
        valid = det.valid & found[:, None]
        delay = (est.window_offset[:, None] + det.lag) / self.fs
        rng = np.where(valid, self.to_range(np.nan_to_num(delay)), np.nan)
        power = np.abs(det.amplitude) ** 2
        # 5. with elevation beams, each detection's elevation from the rows' responses at its delay
        azimuth, elevation, located = self.directions(capture, spec, gate, est.window_offset, det.lag, valid)
        # 6. point cloud: normalize by the scan's (row's) peak, keep what clears the threshold
        scan = build_scan(rng, power, located, azimuth, capture.beam_index, capture.orientation,
                          self.point_threshold_db(), self.point_floor_db(), self.cell_m,
                          elevation, capture.elevation_index)
        return SensingResult(scan, t1 / self.fs, delay, rng, power, valid, det.dft_evaluations, spec,
                             est.window_offset, self)

    def _beam_profile(self, capture: Capture, row: int, window_s: tuple[float, float] | None):
        """T1 (1,) samples, the window offset (1,), the PDP spectrum and the gate of one beam."""
        one = capture.select([row])
        t1, _, est = self.front_end(one)
        offset = est.window_offset
        gate = self.window_gate(one, offset) if window_s is None else self.gate(
            one, offset, np.array([window_s[0]]), np.array([window_s[1]]))
        return t1, offset, pdp_spectrum(est, self.p, self.n), gate

    def beam_delay(self, capture: Capture, row: int, window_s: tuple[float, float] | None = None):
        """(T1, T2) in seconds of the strongest PDP echo on one beam (calibration, eq. (11)).

        ``window_s`` bounds T1 + T2 (default: every lag of the FFT window); the leakage is
        cancelled when the hardware delay is known. T2 is NaN when nothing is found.
        """
        t1, offset, spec, gate = self._beam_profile(capture, row, window_s)
        det = detect_single(spec, gate, self.cfg, self.refiner)
        t2 = (offset[0] + det.lag[0, 0] - t1[0]) / self.fs if det.valid[0, 0] else np.nan
        return float(t1[0] / self.fs), float(t2)

    def beam_peaks(self, capture: Capture, row: int) -> np.ndarray:
        """T1 + T2 in seconds (K̂,) of the K̂ strongest refined PDP peaks of one beam anywhere in its FFT
        window, leakage cancelled when its delay is known (NaN: fewer peaks)."""
        _, offset, spec, gate = self._beam_profile(capture, row, None)
        _, refined, ok = pdp_peaks(spec, gate, self.cfg, self.refiner)
        return np.where(ok[0], (offset[0] + refined.lag[0]) / self.fs, np.nan)
