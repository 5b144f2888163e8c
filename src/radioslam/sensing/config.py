"""Receiver settings (paper §III, §IV-A). Options are Enums; a factory builds each stage from these."""

from __future__ import annotations

from enum import Enum
from pathlib import Path

from pydantic import BaseModel, ConfigDict, Field

from radioslam.choices import Detector, PointFilter, Refinement
from radioslam.config_file import load_section
from radioslam.sensing.errors import SensingError


class CfarKind(str, Enum):
    CA = "ca"  # cell averaging
    OS = "os"  # ordered statistic


class Taper(str, Enum):
    """Window across the active subcarriers before the IFFT."""

    NONE = "none"
    HANN = "hann"


# the range gate's default: with the leakage's lag measured at calibration the gate stops where the
# arrays' far field starts (2D²/λ = 0.26 m for 8 elements at 28 GHz) with margin, and a target 0.41
# sample from the leakage is estimated jointly with it; without, the leakage is assumed at b/c and a
# lag error would leave a residual within a cell of it, so the gate keeps clear of that cell
NEAR_GATE_M = 0.5
FAR_GATE_M = 1.5


class SensingConfig(BaseModel):
    """Every receiver parameter. Defaults follow the paper; ranges in metres."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    detector: Detector = Detector.SINGLE
    peaks: int = Field(3, ge=1, le=16)  # K̂, the IFFT peaks refined per beam (§III-A)
    refine: Refinement = Refinement.BRACKETED
    precision_m: float = Field(0.001, ge=1e-6, le=1.0)  # refinement stops at this range precision
    max_iterations: int = Field(20, ge=0, le=40)  # refinement steps at most
    decimation: int = Field(4, ge=1, le=16)  # PSS synchronization rate f_s/4 (§III-C)
    min_range_m: float | None = Field(None, ge=0)  # gate; None: NEAR_GATE_M with a calibrated leakage, else FAR
    # what cancelling the leakage may leave, relative to it (a lag 0.02 sample off leaves −30 dB): the
    # residual's profile at this level joins the detection threshold, so it never becomes a target
    leakage_residual_db: float = Field(-30.0, le=0)
    max_range_m: float | None = Field(None, gt=0, le=1000.0)  # None: the radio's max_range_m
    noise_pfa: float = Field(1e-6, gt=0, lt=1)  # a peak must clear the noise floor at this Pfa
    point_threshold_db: float | None = Field(None, le=0)  # None: the radio's (−13 dB, §IV-A) for single,
    # and for multi this one: cancellation removes range sidelobes and CFAR bounds false alarms, so the
    # threshold only has to reject beam sidelobes (two-way −25.6 dB) while keeping targets behind glass
    multi_threshold_db: float = Field(-25.0, le=0)
    # single detector: the paper's threshold applied per range, not per scan. A beam sidelobe of an
    # echo has that echo's range, so only there can a weak detection be one; a far wall 15 dB below
    # the near walls (a corridor's end) is kept. The floor is the two-way beam sidelobe level.
    point_filter: PointFilter = PointFilter.SAME_RANGE
    point_floor_db: float = Field(-25.0, le=0)
    cfar: CfarKind = CfarKind.CA
    cfar_guard: int = Field(3, ge=0, le=256)
    cfar_train: int = Field(16, ge=2, le=1024)
    cfar_pfa: float = Field(1e-6, gt=0, lt=1)
    max_targets: int = Field(3, ge=1, le=16)  # per beam, multi-target mode
    relax_passes: int = Field(1, ge=0, le=20)  # single: cyclic re-estimation passes before the joint polish
    taper: Taper = Taper.NONE


def load_sensing_config(path: str | Path) -> SensingConfig:
    """The ``sensing:`` section of a YAML config file (other sections are left to their stages)."""
    return load_section(path, "sensing", SensingConfig, SensingError)
