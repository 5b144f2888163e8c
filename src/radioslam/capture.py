"""The Capture: what the sensing receiver sees at one pose (DESIGN.md §1).

One capture holds every swept beam (4 orientations × 47 beams, orientation-major)
and the metadata a receiver needs: beam angles, the symbol schedule, the
transmitted bits, and the radio parameters. It is the same whether it comes from
the simulator or from a SigMF recording; it carries no ground truth about the
scene (``radio.hardware_delay_s`` is the configured value, which the receiver
must calibrate rather than read).

waveform mode: ``samples`` (B, W) complex64; window sample 0 is the start of the
    beam's transmitted burst: its PSS symbol, then its R sensing symbols, sent
    back to back, each with the NR cyclic prefix of its slot position.
grid mode: ``grid`` (B, R, n_sc) complex64, the sensing symbols' resource
    elements (eq. (4)) for FFT windows opened ``fft_offset_samples`` after each
    symbol's useful part begins.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum

import numpy as np

from radioslam.config import RadioConfig
from radioslam.errors import RadioslamError
from radioslam.nr.numerology import Numerology
from radioslam.nr.ofdm import symbol_starts
from radioslam.nr.qam import qam16_energy, qam16_modulate


class CaptureMode(str, Enum):
    WAVEFORM = "waveform"
    GRID = "grid"


class CaptureError(RadioslamError):
    """A capture whose arrays disagree with each other or with its radio."""


@dataclass(frozen=True, eq=False)
class Capture:
    radio: RadioConfig
    mode: CaptureMode
    pose_index: int
    orientation: np.ndarray  # (B,) k
    beam_index: np.ndarray  # (B,) codebook index i
    beam_angle_rad: np.ndarray  # (B,) terminal frame
    ssb_index: np.ndarray  # (B,)
    symbol_indices: np.ndarray  # (B, 1 + R): PSS symbol, then sensing symbols
    tx_bits: np.ndarray  # (B, R, 4·n_sc) uint8
    samples: np.ndarray | None = None  # (B, W) complex64
    grid: np.ndarray | None = None  # (B, R, n_sc) complex64
    fft_offset_samples: int = 0
    source: str = field(default="memory")
    beam_elevation_rad: np.ndarray | None = None  # (B,) elevation each beam points at; None: all 0 (flat)
    elevation_index: np.ndarray | None = None  # (B,) elevation codebook index j; None: all 0 (flat)

    def __post_init__(self) -> None:
        for name in ("beam_elevation_rad", "elevation_index"):  # a flat capture (or recording) has none
            if getattr(self, name) is None:
                object.__setattr__(self, name, np.zeros(len(self.beam_index), float if "rad" in name else np.int64))
        self.validate()

    @property
    def n_beams(self) -> int:
        return len(self.beam_index)

    @property
    def numerology(self) -> Numerology:
        return Numerology.from_config(self.radio)

    def tx_symbols(self, dtype=np.complex128, conjugate: bool = False) -> np.ndarray:
        """The transmitted 16-QAM sensing symbols (B, R, n_sc), or their conjugates."""
        return qam16_modulate(self.tx_bits, dtype, conjugate=conjugate)

    def tx_energy(self, dtype=np.float32) -> np.ndarray:
        """|x|² (B, R, n_sc) of the transmitted sensing symbols."""
        return qam16_energy(self.tx_bits, dtype)

    def cp_lengths(self) -> np.ndarray:
        """CP length (B, 1 + R) of every symbol in each beam's window."""
        return self.numerology.cp_lengths(self.symbol_indices)

    def useful_starts(self) -> np.ndarray:
        """Window sample (B, 1 + R) where each symbol's useful part (after its CP) starts.

        The transmitted burst sends the window's symbols back to back from sample 0;
        an echo delayed by d samples has its useful parts at ``useful_starts() + d``.
        """
        cp = self.cp_lengths()
        return symbol_starts(cp, self.radio.fft_size) + cp

    def select(self, rows: np.ndarray | list[int]) -> "Capture":
        """The same capture restricted to some beams (rows of the beam axis)."""
        rows = np.atleast_1d(np.asarray(rows, dtype=np.int64))

        def pick(a):
            return None if a is None else a[rows]

        return Capture(radio=self.radio, mode=self.mode, pose_index=self.pose_index,
                       orientation=self.orientation[rows], beam_index=self.beam_index[rows],
                       beam_angle_rad=self.beam_angle_rad[rows], ssb_index=self.ssb_index[rows],
                       symbol_indices=self.symbol_indices[rows], tx_bits=self.tx_bits[rows],
                       samples=pick(self.samples), grid=pick(self.grid),
                       fft_offset_samples=self.fft_offset_samples, source=self.source,
                       beam_elevation_rad=self.beam_elevation_rad[rows], elevation_index=self.elevation_index[rows])

    def validate(self) -> None:
        b, r, n_sc = self.n_beams, self.radio.symbols_per_beam, self.radio.n_subcarriers
        checks = [
            ("orientation", self.orientation.shape == (b,)),
            ("beam_angle_rad", self.beam_angle_rad.shape == (b,)),
            ("beam_elevation_rad", self.beam_elevation_rad.shape == (b,)),
            ("elevation_index", self.elevation_index.shape == (b,)),
            ("ssb_index", self.ssb_index.shape == (b,)),
            ("symbol_indices", self.symbol_indices.shape == (b, 1 + r)),
            ("tx_bits", self.tx_bits.shape == (b, r, 4 * n_sc)),
        ]
        if self.mode is CaptureMode.WAVEFORM:
            checks.append(("samples", self.samples is not None and self.samples.ndim == 2
                           and self.samples.shape[0] == b))
        else:
            checks.append(("grid", self.grid is not None and self.grid.shape == (b, r, n_sc)))
        for name, ok in checks:
            if not ok:
                raise CaptureError("shape disagrees with the beam count or radio", file=self.source, field=name)
        data = self.samples if self.mode is CaptureMode.WAVEFORM else self.grid
        rails = data.view(np.float32) if data.dtype == np.complex64 else data
        if np.isfinite(np.sum(rails)):  # one pass: a NaN or ±inf anywhere makes the sum so (overflow: exact check)
            return
        bad = ~np.isfinite(rails)
        if bad.any():
            first = int(np.flatnonzero(bad.reshape(b, -1).any(axis=1))[0])
            raise CaptureError("contains NaN or infinite samples", file=self.source,
                               field=f"beam {first} (orientation {self.orientation[first]}, "
                                     f"index {self.beam_index[first]})")
