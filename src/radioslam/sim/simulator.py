"""The echo simulator: scene + pose → Capture (paper §II, §IV-A; eq. (4)).

Main loop per pose, one step per comment; everything inside is vectorized over
beams, paths, symbols and subcarriers.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache, cached_property

import numpy as np
from threadpoolctl import ThreadpoolController

from radioslam.antenna.codebook import BeamSet
from radioslam.capture import Capture, CaptureMode
from radioslam.choices import ChannelKind
from radioslam.config import SPEED_OF_LIGHT, DataMode, RadioConfig
from radioslam.nr.frame import FrameSchedule
from radioslam.nr.numerology import Numerology
from radioslam.nr.pss import pss_grid
from radioslam.nr.qam import qam16_modulate, random_bits
from radioslam.scene.model import Scene
from radioslam.sim.channel import beam_path_gains, binned_channel_response
from radioslam.sim.channel_backend import ChannelBackend, TraceStore, make_channel
from radioslam.sim.errors import SimulationError
from radioslam.sim.impairments import receiver_chain, transmitter_chain
from radioslam.sim.memory import MemoryEstimate, pose_memory
from radioslam.sim.noise import add_noise, noise_variance
from radioslam.sim.paths import EchoPaths
from radioslam.sim.phase_noise import OscillatorPhases
from radioslam.sim.waveform import BurstSymbols, synthesize_windows

WINDOW_GUARD_SAMPLES = 16
# what a seed gives: raised whenever the same seed would draw other samples (2: session 14's Box–Muller
# noise), so that caches of simulated captures or scans can tell them apart
RANDOM_STREAM_VERSION = 2


@cache
def blas_controller() -> ThreadpoolController:
    """The BLAS libraries loaded by numpy and scipy (found once)."""
    return ThreadpoolController()


def draw_tx_bits(radio: RadioConfig, n_beams: int, rng: np.random.Generator) -> np.ndarray:
    """Random payload bits (B, R, 4·n_sc): independent per symbol, or repeated (identical)."""
    r, width = radio.symbols_per_beam, 4 * radio.n_subcarriers
    if radio.data is DataMode.IDENTICAL:
        one = random_bits(rng, (n_beams, 1, width))
        return np.repeat(one, r, axis=1)
    return random_bits(rng, (n_beams, r, width))


@dataclass(frozen=True)
class Simulator:
    """Simulates captures of one scene (or of given echo paths).

    Build with :meth:`from_scene`, or :meth:`from_radio` for paths that do not come
    from a scene (point targets, calibration targets). ``rows`` selects a subset of
    the 188 beams (all by default), e.g. only the boresight beam of a ranging trial.
    """

    scene: Scene | None
    radio: RadioConfig
    mode: CaptureMode
    numerology: Numerology
    schedule: FrameSchedule
    beams: BeamSet
    rows: np.ndarray  # (B,) indices into the full beam set
    noise_variance: float
    window_length: int
    window_symbols: np.ndarray  # (B, 1 + R) absolute symbol indices, the same at every pose
    window_cp: np.ndarray  # (B, 1 + R) their CP lengths
    pss_symbol: np.ndarray  # (n_sc,) the PSS on the active subcarriers
    channel_kind: ChannelKind = ChannelKind.BUILTIN  # where a scene's echo paths come from
    trace_cache: TraceStore | None = None  # where the channel keeps its traces (make_channel), or None

    @classmethod
    def from_scene(cls, scene: Scene, mode: CaptureMode = CaptureMode.WAVEFORM,
                   rows: np.ndarray | None = None, channel: ChannelKind = ChannelKind.BUILTIN,
                   trace_cache: TraceStore | None = None) -> "Simulator":
        return cls.from_radio(scene.radio, mode, scene, rows, channel, trace_cache)

    @classmethod
    def from_radio(cls, radio: RadioConfig, mode: CaptureMode = CaptureMode.WAVEFORM,
                   scene: Scene | None = None, rows: np.ndarray | None = None,
                   channel: ChannelKind = ChannelKind.BUILTIN,
                   trace_cache: TraceStore | None = None) -> "Simulator":
        num = Numerology.from_config(radio)
        schedule = FrameSchedule.from_config(radio)
        beams = BeamSet.from_config(radio)
        rows = np.arange(len(beams)) if rows is None else np.asarray(rows, dtype=np.int64)
        symbols = schedule.window_symbols(beams.orientation, beams.slot)[rows]
        cp = num.cp_lengths(symbols)
        longest_delay = radio.hardware_delay_s + max(radio.impairments.hardware_delay_drift_s, 0.0) + \
            (2 * radio.max_range_m + radio.array_baseline_m) / SPEED_OF_LIGHT
        # the window length depends on the radio only, never on the beam subset
        all_cp = num.cp_lengths(schedule.window_symbols(beams.orientation, beams.slot))
        window = int((all_cp + num.fft_size).sum(axis=1).max()
                     + np.ceil(longest_delay * num.sample_rate_hz) + WINDOW_GUARD_SAMPLES)
        pss = pss_grid(radio.pss, radio.n_id2, num.subcarrier_indices())
        return cls(scene, radio, mode, num, schedule, beams, rows, noise_variance(radio), window, symbols, cp, pss,
                   ChannelKind(channel), trace_cache)

    @cached_property
    def channel(self) -> ChannelBackend | None:
        """The scene's channel backend, built when first asked for (a memory estimate needs none; Sionna's
        scene costs a second); None without a scene."""
        return None if self.scene is None else make_channel(self.channel_kind, self.scene, self.radio,
                                                            self.trace_cache)

    def memory(self) -> MemoryEstimate:
        """What simulating one pose needs, before anything is allocated (:mod:`radioslam.sim.memory`)."""
        extrude = None if self.scene is None else self.scene.spec.extrude
        planes = 0 if extrude is None else (extrude.floor is not None) + (extrude.ceiling is not None)
        planes = 2 if self.scene is not None and self.scene.spec.mitsuba is not None else planes  # closed, likely
        return pose_memory(len(self.rows), self.window_length, self.radio,
                           0 if self.scene is None else len(self.scene.segments), channel=self.channel_kind,
                           planes=planes)

    def timing_offset(self) -> int:
        """Grid mode's FFT window timing: ⌊T_H·f_s⌋ samples after each useful part starts."""
        return int(np.floor(self.radio.hardware_delay_s * self.numerology.sample_rate_hz))

    def simulate_pose(self, pose_index: int, rng: np.random.Generator) -> Capture:
        # 1. echo paths of this pose from the channel backend (delays without the hardware delay)
        paths = self.channel.paths(self.scene.poses[pose_index])
        return self.capture_from_paths(paths, rng, pose_index)

    def capture_from_paths(self, paths: EchoPaths, rng: np.random.Generator, pose_index: int = 0) -> Capture:
        """The capture of echo paths (over-the-air delays; the hardware delay is added here).

        Its matrix products are small: BLAS runs single-threaded meanwhile, so that its idle
        threads do not spin against the synthesis's and the noise's own two workers."""
        with blas_controller().limit(limits=1, user_api="blas"):
            return self._capture_from_paths(paths, rng, pose_index)

    def _capture_from_paths(self, paths: EchoPaths, rng: np.random.Generator, pose_index: int) -> Capture:
        radio, num = self.radio, self.numerology
        # 2. two-way beam gain ϖ of every path on every beam (eq. (4))
        paths = paths.by_delay()  # the order the delay bins want: no reordered copy of the gains
        gains = beam_path_gains(self.beams, paths)
        gains = gains if len(self.rows) == len(self.beams) else gains[self.rows]
        delays = paths.delay_s + radio.hardware_delay_s + radio.impairments.hardware_delay_drift_s
        # 3. what each beam transmits: PSS symbol, then R symbols of random 16-QAM (through the PA in 4a/4b)
        n_beams = len(self.rows)
        bits = draw_tx_bits(radio, n_beams, rng)
        p = num.subcarrier_indices()
        # the channel H_i(p) of eq. (4), split by the sample at which each path arrives
        d_min, _, cumulative = binned_channel_response(gains, delays * num.sample_rate_hz, p,
                                                       radio.subcarrier_spacing_hz, num.sample_rate_hz,
                                                       row_blocks=min(radio.orientations, n_beams))
        common = dict(radio=radio, pose_index=pose_index, orientation=self.beams.orientation[self.rows],
                      beam_index=self.beams.index[self.rows], beam_angle_rad=self.beams.angle[self.rows],
                      beam_elevation_rad=self.beams.elevation[self.rows],
                      elevation_index=self.beams.elevation_index[self.rows],
                      ssb_index=self.schedule.ssb_index(self.beams.slot[self.rows]),
                      symbol_indices=self.window_symbols, tx_bits=bits)
        if self.mode is CaptureMode.GRID:
            if radio.impairments.time_domain:
                raise SimulationError("I/Q imbalance and the ADC act on the waveform: simulate in waveform mode",
                                      field="radio.impairments")
            # 4a. resource grid directly, y = H(p)·x + z (eq. (4)), at the receiver's FFT timing
            h = cumulative[-1] * np.exp(2j * np.pi * p * self.timing_offset() / num.fft_size)
            sent = transmitter_chain(qam16_modulate(bits), num, radio.impairments)
            grid = add_noise(h[:, None, :] * sent, self.noise_variance, rng)
            return Capture(mode=CaptureMode.GRID, grid=grid, fft_offset_samples=self.timing_offset(), **common)
        # 4b. time-domain windows: every path at its exact fractional delay
        tx = BurstSymbols(self.pss_symbol, bits)  # mapped block by block inside the synthesis
        lo = self.oscillator_phases(n_beams, rng)  # the LO's phase noise, if any
        if radio.impairments.pa_backoff_db is not None or lo is not None:  # they act on the whole grid
            tx = transmitter_chain(tx[np.arange(n_beams)], num, radio.impairments)  # the PA's compression
            tx = tx if lo is None else lo.transmitted(tx, self.window_cp, num)
        clean = synthesize_windows(tx, self.window_cp, cumulative, d_min, num, self.window_length)
        if lo is not None:
            clean = lo.received(clean)
        # 5. AWGN at the ★ SNR of the reference echo, then the receiver's I/Q imbalance and ADC (if any)
        received = add_noise(clean, self.noise_variance, rng, inplace=True)
        return Capture(mode=CaptureMode.WAVEFORM, samples=receiver_chain(received, radio.impairments), **common)

    def oscillator_phases(self, n_beams: int, rng: np.random.Generator) -> OscillatorPhases | None:
        """The LO's phase over every beam window (drawn only when the radio has phase noise)."""
        imp, fs = self.radio.impairments, self.numerology.sample_rate_hz
        if imp.phase_noise_linewidth_hz == 0.0:
            return None
        latency = int(round((self.radio.hardware_delay_s + imp.hardware_delay_drift_s) * fs))
        return OscillatorPhases.draw(rng, n_beams, self.window_length, latency, imp.phase_noise_linewidth_hz, fs,
                                     imp.oscillators)

    def simulate(self, seed: int, skip: frozenset[int] = frozenset()):
        """Captures of every pose but those in ``skip``; pose i draws from its own child of
        ``SeedSequence(seed)``, so a pose's capture is the same whichever others are simulated."""
        children = np.random.SeedSequence(seed).spawn(len(self.scene.poses))
        for i, child in enumerate(children):
            if i not in skip:
                yield self.simulate_pose(i, np.random.default_rng(child))
