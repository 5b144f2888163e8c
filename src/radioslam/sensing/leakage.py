"""The TX→RX leakage of every beam, as calibrated (issue #13, point 2).

A full-duplex terminal hears its own transmission through the coupling between its TX and RX
arrays: one echo-like path per beam whose amplitude and phase follow the beams' weights (the
coupling of two steered arrays, 22 dB stronger at broadside than at the codebook's edge) and whose
delay is the coupling path's, b/c between stacked arrays plus whatever the housing adds. At this
bandwidth (1.22 m per range cell) all of it is one tap per beam.

The receiver cancels it before detection (:mod:`radioslam.sensing.detect`): at the lag measured
here, with an amplitude fitted to each capture jointly with the targets (so a drift of the
leakage's gain or phase since calibration is absorbed, and a target 0.4 sample away stays apart);
what a wrong lag would leave, a residual ``leakage_residual_db`` below the leakage, is kept in the
detection threshold. Without a measured lag the receiver assumes b/c and keeps its gate at
:data:`~radioslam.sensing.config.FAR_GATE_M`.

Measured from a capture with nothing in range (:func:`radioslam.sensing.calibration.measure_leakage`):
every beam's strongest echo is the leakage, refined like any target. Stored in ``calibration.json``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from radioslam.sensing.errors import SensingError


@dataclass(frozen=True)
class LeakageModel:
    """Per beam (L,), keyed by (orientation, codebook index, elevation index): the leakage's delay after
    the hardware delay T_H (T1 + T2 − T_H, ≈ b/c) and its complex amplitude at calibration."""

    orientation: np.ndarray
    beam_index: np.ndarray
    delay_s: np.ndarray
    amplitude: np.ndarray
    elevation_index: np.ndarray | None = None  # None: a flat scan's, all 0

    def __post_init__(self) -> None:
        if self.elevation_index is None:
            object.__setattr__(self, "elevation_index", np.zeros(len(self.orientation), np.int64))

    @staticmethod
    def _key(orientation, beam_index, elevation_index) -> np.ndarray:
        """One integer per beam (codebook indices |i|, |j| < 512 for up to 10 bits)."""
        as_int = [np.asarray(a, dtype=np.int64) for a in (orientation, beam_index, elevation_index)]
        return (as_int[0] * 1024 + as_int[1]) * 1024 + as_int[2]

    def rows_of(self, orientation: np.ndarray, beam_index: np.ndarray, source: str = "",
                elevation_index: np.ndarray | None = None) -> np.ndarray:
        """Index (B,) into this model of each beam of a capture; a beam it lacks is an error."""
        key = self._key(orientation, beam_index, np.zeros_like(beam_index) if elevation_index is None
                        else elevation_index)
        known = self._key(self.orientation, self.beam_index, self.elevation_index)
        order = np.argsort(known)
        pos = np.clip(np.searchsorted(known[order], key), 0, len(known) - 1)
        rows = order[pos]
        missing = known[rows] != key
        if missing.any():
            k = int(np.flatnonzero(missing)[0])
            raise SensingError(f"beam (orientation {int(np.asarray(orientation)[k])}, index "
                               f"{int(np.asarray(beam_index)[k])}) has no calibrated leakage", file=source,
                               field="calibration.leakage")
        return rows

    def to_dict(self) -> dict:
        return {"method": "strongest echo of a capture with nothing in range, per beam",
                "orientation": self.orientation.astype(int).tolist(),
                "beam_index": self.beam_index.astype(int).tolist(),
                **({"elevation_index": self.elevation_index.astype(int).tolist()} if self.elevation_index.any()
                   else {}),
                "delay_s": self.delay_s.tolist(), "amplitude_re": self.amplitude.real.tolist(),
                "amplitude_im": self.amplitude.imag.tolist()}

    @classmethod
    def from_dict(cls, doc: dict) -> "LeakageModel":
        """Raises ``ValueError`` naming the field that is wrong."""
        fields = ("orientation", "beam_index", "delay_s", "amplitude_re", "amplitude_im")
        if isinstance(doc, dict) and "elevation_index" in doc:  # optional: elevation beams (issue #16)
            fields += ("elevation_index",)
        arrays = {}
        for name in fields:
            value = doc.get(name) if isinstance(doc, dict) else None
            try:
                arrays[name] = np.asarray(value, dtype=np.float64)
            except (TypeError, ValueError):
                raise ValueError(f"leakage.{name}: must be a list of numbers") from None
            if arrays[name].ndim != 1 or not np.isfinite(arrays[name]).all():
                raise ValueError(f"leakage.{name}: must be a list of finite numbers")
        if len({len(a) for a in arrays.values()}) != 1 or len(arrays["delay_s"]) == 0:
            raise ValueError("leakage: its lists must be non-empty and of one length")
        arrays.setdefault("elevation_index", np.zeros(len(arrays["orientation"])))
        for name in ("orientation", "beam_index", "elevation_index"):  # keys: whole numbers (orientation ≥ 0)
            if np.any(arrays[name] != np.round(arrays[name])) or (name == "orientation" and np.any(arrays[name] < 0)):
                raise ValueError(f"leakage.{name}: must be whole numbers" + (" ≥ 0" if name == "orientation" else ""))
        beams = set(zip(arrays["orientation"], arrays["beam_index"], arrays["elevation_index"]))
        if len(beams) != len(arrays["orientation"]):
            raise ValueError("leakage: a beam (orientation, beam_index, elevation_index) is listed twice")
        if np.any(np.abs(arrays["delay_s"]) > 1e-6):
            raise ValueError("leakage.delay_s: must be within ±1 µs of the hardware delay")
        return cls(arrays["orientation"].astype(np.int64), arrays["beam_index"].astype(np.int64), arrays["delay_s"],
                   arrays["amplitude_re"] + 1j * arrays["amplitude_im"], arrays["elevation_index"].astype(np.int64))
