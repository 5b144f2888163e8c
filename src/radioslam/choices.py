"""Enums the core defines and the command line offers as choices, kept free of numpy and pydantic so that
``radioslam --help`` stays quick (the CLI imports the stages lazily)."""

from __future__ import annotations

from enum import Enum


class ChannelKind(str, Enum):
    """``--channel`` ★ (issue #16): where the echo paths come from, the built-in caster or Sionna RT."""

    BUILTIN = "builtin"
    SIONNA = "sionna"


class Detector(str, Enum):
    """How targets are picked from each beam's range profile."""

    SINGLE = "single"  # the paper's single target per beam: the strongest peak (§III-A)
    MULTI = "multi"  # CFAR + successive cancellation on the matched-filter profile (§III-B)


class PointFilter(str, Enum):
    """Which single-target detections become points (§IV-A: the −13 dB rule against sidelobe returns)."""

    SCAN_PEAK = "scan-peak"  # the paper's: within the threshold of the scan's strongest detection
    # within the threshold of the strongest detection at the same range (±1 range cell), where a beam
    # sidelobe of that echo would appear, and within point_floor_db of the scan's peak
    SAME_RANGE = "same-range"


class Refinement(str, Enum):
    """How an integer range-profile peak is refined to a fractional lag (T2)."""

    BRACKETED = "bracketed"  # both sides on a quarter-sample grid, safeguarded Newton per lobe that may win
    PAPER_BISECTION = "paper-bisection"  # the paper's fractional-IFFT bisection (§III-A), to reproduce it


class Experiment(str, Enum):
    """``radioslam reproduce`` ★: the paper's experiments, and Table I under each hardware impairment."""

    TABLE1 = "table1"
    FIG5 = "fig5"
    FIG8 = "fig8"
    FIG6 = "fig6"
    IMPAIRMENTS = "impairments"
    ALL = "all"


class ImpairmentProfile(str, Enum):
    """A radio's hardware profile for ``reproduce table1 --impairments`` (the keys of
    :data:`radioslam.eval.experiments.impairments.PROFILES`, tested equal)."""

    IDEAL = "ideal"
    IQ = "iq"
    ADC = "adc"
    PA = "pa"
    ELEMENTS = "elements"
    DRIFT = "drift"
    PHASE_NOISE = "phase-noise"
    LEAKAGE = "leakage"
    EXTENDED = "extended"
    PROTOTYPE = "prototype"
