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
    """Per beam (L,), keyed by (orientation, codebook index): the leakage's delay after the hardware
    delay T_H (T1 + T2 − T_H, ≈ b/c) and its complex amplitude at calibration."""

    orientation: np.ndarray
    beam_index: np.ndarray
    delay_s: np.ndarray
    amplitude: np.ndarray

    def rows_of(self, orientation: np.ndarray, beam_index: np.ndarray, source: str = "") -> np.ndarray:
        """Index (B,) into this model of each beam of a capture; a beam it lacks is an error."""
        key = np.asarray(orientation, dtype=np.int64) * 1024 + np.asarray(beam_index, dtype=np.int64)
        known = self.orientation.astype(np.int64) * 1024 + self.beam_index.astype(np.int64)
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
                "delay_s": self.delay_s.tolist(), "amplitude_re": self.amplitude.real.tolist(),
                "amplitude_im": self.amplitude.imag.tolist()}

    @classmethod
    def from_dict(cls, doc: dict) -> "LeakageModel":
        """Raises ``ValueError`` naming the field that is wrong."""
        fields = ("orientation", "beam_index", "delay_s", "amplitude_re", "amplitude_im")
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
        for name in ("orientation", "beam_index"):  # keys: whole numbers (orientation also ≥ 0)
            if np.any(arrays[name] != np.round(arrays[name])) or (name == "orientation" and np.any(arrays[name] < 0)):
                raise ValueError(f"leakage.{name}: must be whole numbers" + (" ≥ 0" if name == "orientation" else ""))
        if len(set(zip(arrays["orientation"], arrays["beam_index"]))) != len(arrays["orientation"]):
            raise ValueError("leakage: a beam (orientation, beam_index) is listed twice")
        if np.any(np.abs(arrays["delay_s"]) > 1e-6):
            raise ValueError("leakage.delay_s: must be within ±1 µs of the hardware delay")
        return cls(arrays["orientation"].astype(np.int64), arrays["beam_index"].astype(np.int64), arrays["delay_s"],
                   arrays["amplitude_re"] + 1j * arrays["amplitude_im"])
