"""5G NR physical layer for sensing: numerology, frame schedule, 16-QAM, PSS, CP-OFDM."""

from radioslam.nr.frame import FrameSchedule, case_d_ssb_starts
from radioslam.nr.numerology import Numerology, NumerologyError
from radioslam.nr.ofdm import demodulate, modulate
from radioslam.nr.pss import pss, pss_grid, pss_sequence, pss_zadoff_chu
from radioslam.nr.qam import qam16_demodulate, qam16_modulate, random_bits

__all__ = [
    "FrameSchedule", "Numerology", "NumerologyError", "case_d_ssb_starts", "demodulate",
    "modulate", "pss", "pss_grid", "pss_sequence", "pss_zadoff_chu", "qam16_demodulate",
    "qam16_modulate", "random_bits",
]
