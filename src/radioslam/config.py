"""Radio configuration: the prototype's defaults (paper Table II, §II-D; DESIGN.md §3).

A scene file's optional ``radio:`` block overrides any of these fields. The model
is frozen and rejects unknown keys, so a typo in a scene file is an error, not a
silently ignored setting.
"""

from __future__ import annotations

from enum import Enum

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator

SPEED_OF_LIGHT = 299_792_458.0  # m/s


def bistatic_delay_s(range_m, baseline_m: float):
    """Echo delay 2√(r² + b²/4)/c of a target at horizontal range r, TX and RX arrays stacked b apart."""
    return 2.0 * np.sqrt(np.asarray(range_m, dtype=np.float64) ** 2 + 0.25 * baseline_m**2) / SPEED_OF_LIGHT


class PssKind(str, Enum):
    """Which PSS sequence the SSB carries."""

    M_SEQUENCE = "m-sequence"  # 3GPP TS 38.211 §7.4.2.2
    ZADOFF_CHU = "zadoff-chu"  # the paper's wording (§III-A)


class DataMode(str, Enum):
    """Sensing payload across the R symbols of one beam (paper §III-B, Fig. 5)."""

    DIFFERENT = "different"  # independent 16-QAM per symbol
    IDENTICAL = "identical"  # the same 16-QAM symbol repeated R times


class LeakageCoupling(str, Enum):
    """How the TX→RX leakage differs between beams (its mean power is the radio's isolation)."""

    ARRAYS = "arrays"  # the free-space coupling of the two steered, stacked arrays: 22 dB broadside-to-edge
    UNIFORM = "uniform"  # the same on every beam (one isolation figure; the model before issue #13)


class Oscillators(str, Enum):
    """Where the transmitter's and the receiver's carriers come from."""

    SHARED = "shared"  # one LO for both, as in a monostatic terminal: phase noise cancels but over the delay
    SEPARATE = "separate"  # two free-running LOs: the phase noise of both adds up, whatever the delay


class Impairments(BaseModel):
    """Hardware impairments of the simulated front end (issue #13), each off by default; their physics
    in :mod:`radioslam.sim.impairments`. I/Q imbalance and the ADC act on the waveform (waveform mode)."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    iq_gain_db: float = Field(0.0, ge=-6.0, le=6.0)  # receiver Q-rail gain relative to I
    iq_phase_deg: float = Field(0.0, ge=-45.0, le=45.0)  # receiver quadrature error
    adc_bits: int | None = Field(None, ge=1, le=24)  # None: an ideal converter
    adc_backoff_db: float = Field(12.0, ge=0.0, le=40.0)  # full scale above each rail's RMS (the AGC's set point)
    element_gain_db: float = Field(0.0, ge=0.0, le=6.0)  # σ of each element's gain error, both arrays
    element_phase_deg: float = Field(0.0, ge=0.0, le=90.0)  # σ of each element's phase error
    element_seed: int = Field(0, ge=0)  # the arrays' errors belong to the hardware: drawn once, from this
    pa_backoff_db: float | None = Field(None, ge=-10.0, le=30.0)  # PA saturation above the TX RMS; None: linear
    pa_smoothness: float = Field(2.0, gt=0.0, le=20.0)  # Rapp's p (large: a hard limiter)
    # the hardware delay's change between calibration (eq. (11)) and use: every sensing capture's T_H is
    # hardware_delay_s + this, the calibration plates' hardware_delay_s
    hardware_delay_drift_s: float = Field(0.0, ge=-1e-6, le=1e-6)
    # the TX→RX leakage's change between its calibration (a capture with nothing in range) and use: a gain
    # and a phase on every beam's coupling (temperature, the PA's and LNA's operating point)
    # Wiener phase noise of the LO, its 3 dB (Lorentzian) linewidth; the TX side is applied per OFDM symbol
    # as if cyclic, valid while 2π·linewidth·(N + CP)/f_s ≪ 1 (the bound keeps that below 0.06 rad²)
    phase_noise_linewidth_hz: float = Field(0.0, ge=0.0, le=1e3)
    oscillators: Oscillators = Oscillators.SHARED
    # the walls' specular return as physical-optics facets along each wall (a finite plate is an extended
    # target, not a point: its Fresnel zones and edges are in the echo) instead of one image source
    specular_facets: bool = False
    leakage_drift_db: float = Field(0.0, ge=-6.0, le=6.0)
    leakage_drift_deg: float = Field(0.0, ge=-180.0, le=180.0)

    def at_calibration(self) -> "Impairments":
        """The same hardware when it was calibrated: no drift yet."""
        return self.model_copy(update={"hardware_delay_drift_s": 0.0, "leakage_drift_db": 0.0,
                                       "leakage_drift_deg": 0.0})

    @property
    def leakage_drift(self) -> complex:
        """The factor on every beam's leakage since calibration."""
        return complex(10.0 ** (self.leakage_drift_db / 20.0) * np.exp(1j * np.radians(self.leakage_drift_deg)))

    @property
    def time_domain(self) -> bool:
        """Whether an impairment acts on the received waveform (grid mode cannot model it)."""
        return (self.iq_gain_db != 0.0 or self.iq_phase_deg != 0.0 or self.adc_bits is not None
                or self.phase_noise_linewidth_hz > 0.0)


class RadioConfig(BaseModel):
    """Every radio parameter of the simulated prototype, in SI units."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    carrier_hz: float = Field(28e9, gt=0, le=3e11)
    fft_size: int = Field(1024, ge=128, le=4096)  # NR: at most 4096 (38.211)
    n_subcarriers: int = Field(792, ge=12, le=3300)  # ≤ 275 resource blocks
    subcarrier_spacing_hz: float = Field(120e3, gt=0, le=960e3)
    array_elements: int = Field(8, ge=2, le=256)
    codebook_bits: int = Field(6, ge=2, le=10)
    beams_per_side: int = Field(23, ge=0)  # i = -23..23: 47 beams, ±45.95°
    orientations: int = Field(4, ge=1, le=8)
    # ★ elevation beams of the 8×8 array (a DFT codebook over its columns, issue #16): 1, today's flat scan;
    # odd, so that one beam is horizontal (the SLAM's slice)
    elevation_beams: int = Field(1, ge=1, le=15)
    # spacing of the elevation codebook indices j (ϑ_v = j/2^M); None: 2^M/(2·N) (half the orthogonal
    # spacing, adjacent beams cross at −3.9 dB so that heights can be interpolated between them)
    elevation_step: int | None = Field(None, ge=1)
    # the built-in caster's ray spacing over azimuth and elevation when it traces in 3D (elevation beams)
    ray_spacing_3d_deg: float = Field(2.0, ge=0.1, le=10.0)
    # Sionna RT's diffuse rays per source (each of the 4 orientations' TX): its paths, and so the memory of
    # the beams' gains (beams × paths), grow with it
    sionna_samples: int = Field(200_000, ge=1_000, le=10_000_000)
    symbols_per_frame: int = Field(6, ge=1, le=14)  # sensing symbols per beam per frame
    frames: int = Field(2, ge=1, le=64)  # R = symbols_per_frame * frames = 12
    pss: PssKind = PssKind.M_SEQUENCE
    n_id2: int = Field(0, ge=0, le=2)
    data: DataMode = DataMode.DIFFERENT
    # ★ per-RE SNR of the reference echo (DESIGN.md §2); up to 400 dB: noiseless, for tests
    snr_db: float = Field(10.0, ge=-60.0, le=400.0)
    hardware_delay_s: float = Field(32e-6, ge=0, le=1e-3)
    # TX→RX isolation, mean over the beams: leakage ≈ the 5 m reference echo
    isolation_db: float = Field(70.0, ge=0.0, le=400.0)
    array_baseline_m: float = Field(0.05, ge=0, le=1.0)  # TX/RX array centre spacing
    # the terminal's height above the floor (the middle between its two arrays): what a 3D channel sees
    height_m: float = Field(1.5, gt=0, le=1000.0)
    # the coupling path's delay beyond b/c (feed lines, a reflection inside the housing): the receiver
    # does not assume it, it measures the leakage's delay per beam at calibration
    leakage_excess_delay_s: float = Field(0.0, ge=-5e-9, le=5e-9)
    leakage_coupling: LeakageCoupling = LeakageCoupling.ARRAYS
    element_exponent: float = Field(1.0, ge=0, le=100)  # element power pattern cos^q(θ)
    ray_spacing_deg: float = Field(0.25, ge=0.01, le=2.0)
    max_range_m: float = Field(40.0, gt=0, le=1000.0)
    max_hits: int = Field(3, ge=1, le=8)  # ray continues through transmissive walls
    calibration_targets: int = Field(16, ge=1, le=256)
    calibration_spacing_m: float = Field(0.8, gt=0, le=100.0)
    point_threshold_db: float = Field(-13.0, le=0)
    impairments: Impairments = Impairments()

    @model_validator(mode="after")
    def _check(self) -> "RadioConfig":
        if self.n_subcarriers > self.fft_size:
            raise ValueError("n_subcarriers must not exceed fft_size")
        if self.n_subcarriers % 12:
            raise ValueError("n_subcarriers must be a whole number of resource blocks (12)")
        if self.beams_per_side >= 2 ** (self.codebook_bits - 1):
            raise ValueError("beams_per_side must stay below 2^(codebook_bits-1) (|sin θ| < 1)")
        if self.elevation_beams % 2 == 0:
            raise ValueError("elevation_beams must be odd: a symmetric codebook with one horizontal beam")
        u_y, u_z = 2.0 * self.beams_per_side / 2**self.codebook_bits, 2.0 * self.elevation_span / 2**self.codebook_bits
        if u_y**2 + u_z**2 >= 1.0:
            raise ValueError(f"elevation beams up to index {self.elevation_span} with azimuth beams up to "
                             f"{self.beams_per_side} point outside the visible region (u_y² + u_z² ≥ 1)")
        return self

    @property
    def sample_rate_hz(self) -> float:
        return self.fft_size * self.subcarrier_spacing_hz

    @property
    def wavelength_m(self) -> float:
        return SPEED_OF_LIGHT / self.carrier_hz

    @property
    def symbols_per_beam(self) -> int:
        """R, the number of sensing symbols per beam (12 by default)."""
        return self.symbols_per_frame * self.frames

    @property
    def azimuth_beams(self) -> int:
        """Beams of one elevation row of the codebook: 2·beams_per_side + 1 (47)."""
        return 2 * self.beams_per_side + 1

    @property
    def elevation_spacing(self) -> int:
        """The elevation codebook's index step (``elevation_step``, or 2^M/(2N))."""
        return self.elevation_step or max(1, 2**self.codebook_bits // (2 * self.array_elements))

    @property
    def elevation_span(self) -> int:
        """The largest elevation codebook index |j|."""
        return (self.elevation_beams - 1) // 2 * self.elevation_spacing

    @property
    def beams_per_orientation(self) -> int:
        """Beams swept per orientation: azimuth × elevation (47 for the flat scan)."""
        return self.azimuth_beams * self.elevation_beams
