"""The sensing frame schedule (paper §II-D, Fig. 1(c)).

The prototype's 20 ms frame is one SSB burst period: 20 subframes × 8 slots × 14
symbols = 2240 symbols. Its first 5 ms (560 symbols) hold the SSB burst of case D
(3GPP TS 38.213 §4.1, 120 kHz, L_max = 64): SSB n starts at symbol
{4, 8, 16, 20} + 28·m, m ∈ {0,1,2,3, 5,6,7,8, 10,11,12,13, 15,16,17,18}, and
occupies 4 symbols. The 560 − 64·4 = 304 symbols left over are the paper's
"304 reserved symbols": sensing symbols go there.

A burst of one frame serves at most Q = min(64, ⌊304/S⌋) beams (S = 6 sensing symbols
per beam per frame: Q = 50). Beam slot s of an orientation (0 … beams − 1) belongs to
burst g = ⌊s/Q⌋ at position q = s mod Q: it uses SSB q (its PSS is that SSB's first
symbol) and the reserved symbols q·S … q·S + S − 1 of each of ``frames`` consecutive
frames, so every beam gets R = S·frames = 12 sensing symbols. With G = ⌈beams/Q⌉
bursts per orientation, orientation o's burst g uses frames (o·G + g)·frames …
(o·G + g + 1)·frames − 1, and a pose takes orientations·G·frames frames. The flat
scan's 47 beams fit one burst (G = 1, 8 frames a pose); 7 elevation rows of 47 need
G = 7. Symbol indices are absolute: frame·2240 + symbol.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from radioslam.config import RadioConfig
from radioslam.nr.numerology import Numerology, NumerologyError

SUBFRAMES_PER_FRAME = 20
SSB_SYMBOLS = 4
CASE_D_FIRST = np.array([4, 8, 16, 20])
CASE_D_BLOCKS = np.array([0, 1, 2, 3, 5, 6, 7, 8, 10, 11, 12, 13, 15, 16, 17, 18])


def case_d_ssb_starts() -> np.ndarray:
    """First symbol of each of the 64 SSB candidates in a half frame (38.213 §4.1 case D)."""
    return (CASE_D_FIRST[None, :] + 28 * CASE_D_BLOCKS[:, None]).ravel()


@dataclass(frozen=True)
class FrameSchedule:
    """Map from (orientation, beam, repetition) to absolute OFDM symbol indices."""

    numerology: Numerology
    beams: int
    symbols_per_frame: int
    frames: int

    @classmethod
    def from_config(cls, radio: RadioConfig) -> "FrameSchedule":
        return cls(Numerology.from_config(radio), radio.beams_per_orientation,
                   radio.symbols_per_frame, radio.frames)

    def __post_init__(self) -> None:
        if self.numerology.mu != 3:
            raise NumerologyError("the SSB burst pattern (case D) is defined for 120 kHz spacing only")
        if self.beams_per_burst < 1:
            raise NumerologyError(f"{self.symbols_per_frame} symbols per beam exceed "
                                  f"{len(self.reserved_symbols())} reserved symbols")

    @property
    def beams_per_burst(self) -> int:
        """Q: beams one frame's burst serves, bounded by its SSBs and its reserved symbols."""
        return min(len(case_d_ssb_starts()), len(self.reserved_symbols()) // self.symbols_per_frame)

    @property
    def bursts(self) -> int:
        """G: bursts (of ``frames`` frames each) per orientation."""
        return -(-self.beams // self.beams_per_burst)

    @property
    def frames_per_orientation(self) -> int:
        """Frames one orientation's sweep takes: G × frames (a pose: orientations times that)."""
        return self.bursts * self.frames

    def ssb_index(self, beam: np.ndarray | int) -> np.ndarray:
        """SSB (position q in its burst) of each beam slot."""
        return np.asarray(beam) % self.beams_per_burst

    def _first_frame(self, orientation, beam) -> np.ndarray:
        return (np.asarray(orientation) * self.bursts + np.asarray(beam) // self.beams_per_burst) * self.frames

    @property
    def symbols_per_frame_total(self) -> int:
        return SUBFRAMES_PER_FRAME * self.numerology.symbols_per_subframe

    @property
    def burst_symbols(self) -> int:
        """Symbols in the first 5 ms (the SSB half frame)."""
        return 5 * self.numerology.symbols_per_subframe

    def ssb_symbols(self) -> np.ndarray:
        """Every symbol of the half frame that carries an SSB (256 at μ = 3)."""
        starts = case_d_ssb_starts()
        return (starts[:, None] + np.arange(SSB_SYMBOLS)).ravel()

    def reserved_symbols(self) -> np.ndarray:
        """Symbols of the first 5 ms not used by SSBs (304 at μ = 3), in time order."""
        free = np.ones(self.burst_symbols, dtype=bool)
        free[self.ssb_symbols()] = False
        return np.flatnonzero(free)

    @property
    def repetitions(self) -> int:
        """R, sensing symbols per beam."""
        return self.symbols_per_frame * self.frames

    def pss_symbol(self, orientation: np.ndarray | int, beam: np.ndarray | int) -> np.ndarray:
        """Absolute index of the PSS symbol (first SSB symbol) of each beam."""
        frame = self._first_frame(orientation, beam)
        return frame * self.symbols_per_frame_total + case_d_ssb_starts()[self.ssb_index(beam)]

    def sensing_symbols(self, orientation: np.ndarray | int, beam: np.ndarray | int) -> np.ndarray:
        """Absolute indices (..., R) of the sensing symbols of each beam."""
        orientation, beam = np.broadcast_arrays(np.asarray(orientation), np.asarray(beam))
        reserved = self.reserved_symbols()
        within = reserved[self.ssb_index(beam)[..., None] * self.symbols_per_frame + np.arange(self.symbols_per_frame)]
        frame = self._first_frame(orientation, beam)[..., None, None] + np.arange(self.frames)[:, None]  # (..., F, 1)
        symbols = frame * self.symbols_per_frame_total + within[..., None, :]  # (..., F, S)
        return symbols.reshape(*beam.shape, self.repetitions)

    def window_symbols(self, orientation: np.ndarray | int, beam: np.ndarray | int) -> np.ndarray:
        """Absolute indices (..., 1 + R): the PSS symbol, then the R sensing symbols."""
        pss = self.pss_symbol(orientation, beam)
        return np.concatenate([np.asarray(pss)[..., None], self.sensing_symbols(orientation, beam)], axis=-1)
