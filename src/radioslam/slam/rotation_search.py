"""Global rotation search from specular normals (issue #12): the rotation between a scan and a
map is observable from the scan alone, whatever the motion.

Each wall seen by the terminal's 360° sweep leaves an arc whose power profile gives the
wall's normal bearing to ≈ 0.1° (:mod:`radioslam.slam.normals`). A scan at heading θ sees
a wall of world normal ψ at terminal bearing ψ − θ, so the histogram of the scan's normal
bearings is the map's histogram shifted by θ. Their circular cross-correlation (one FFT
each, the Hough-spectrum idea of Censi, Iocchi & Grisetti, "Scan matching in the Hough
domain", ICRA 2005, on normals instead of lines)

    C(θ) = Σ_ψ h_map(ψ) · h_scan(ψ − θ)

peaks at every heading where the scan's walls line up with the map's: the true one and,
in a room of right angles, its 90° and 180° twins. The peaks are candidates, not answers;
a translation search against the map decides between them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.fft

from radioslam.slam.branch_bound import window_angles
from radioslam.slam.config import FrontEndConfig
from radioslam.slam.se2 import wrap_angle


def bearing_histogram(normals: np.ndarray, bin_rad: float, smooth_rad: float) -> np.ndarray:
    """Circular histogram (B,) of the known bearings, each point one count, smoothed by a
    circular Gaussian of ``smooth_rad`` (wrapped: no seam at ±π)."""
    bins = int(round(2 * np.pi / bin_rad))
    known = normals[~np.isnan(normals)]
    index = np.floor(np.mod(known, 2 * np.pi) / (2 * np.pi) * bins).astype(np.int64) % bins
    hist = np.bincount(index, minlength=bins).astype(np.float64)
    offset = wrap_angle(np.arange(bins) * (2 * np.pi / bins))
    kernel = np.exp(-0.5 * (offset / smooth_rad) ** 2)
    return np.real(scipy.fft.ifft(scipy.fft.fft(hist) * scipy.fft.fft(kernel)))


def rotation_correlation(scan_normals: np.ndarray, map_normals: np.ndarray, bin_rad: float,
                         smooth_rad: float) -> np.ndarray:
    """C(θ_b) (B,) for headings θ_b = b·2π/B: the scan's histogram rotated by θ_b against the map's."""
    h_scan = bearing_histogram(scan_normals, bin_rad, smooth_rad)
    h_map = bearing_histogram(map_normals, bin_rad, smooth_rad)
    # Σ_ψ h_map(ψ) h_scan(ψ − θ) is the circular cross-correlation: ifft(F(h_map) · conj(F(h_scan)))
    return np.real(scipy.fft.ifft(scipy.fft.fft(h_map) * np.conj(scipy.fft.fft(h_scan))))


def rotation_candidates(scan_normals: np.ndarray, map_normals: np.ndarray, bin_rad: float, smooth_rad: float,
                        count: int) -> np.ndarray:
    """Headings (≤ count,) of the strongest local maxima of C, strongest first, each refined to
    the vertex of the parabola through its bin and neighbours; empty when either side has no
    normal."""
    if np.isnan(scan_normals).all() or np.isnan(map_normals).all():
        return np.zeros(0)
    c = rotation_correlation(scan_normals, map_normals, bin_rad, smooth_rad)
    left, right = np.roll(c, 1), np.roll(c, -1)
    peaks = np.flatnonzero((c > left) & (c >= right) & (c > 0))
    peaks = peaks[np.argsort(-c[peaks])][:count]
    curvature = left[peaks] - 2 * c[peaks] + right[peaks]
    shift = np.where(curvature < 0, 0.5 * (left[peaks] - right[peaks]) / np.minimum(curvature, -1e-300), 0.0)
    return wrap_angle((peaks + np.clip(shift, -0.5, 0.5)) * (2 * np.pi / len(c)))


def merge_headings(headings: np.ndarray, width: float) -> np.ndarray:
    """The headings with any within ``width`` of an earlier one dropped (earlier ones win)."""
    out: list[float] = []
    for h in np.asarray(headings, dtype=np.float64):
        if all(abs(wrap_angle(h - o)) > width for o in out):
            out.append(float(h))
    return np.array(out)


@dataclass(frozen=True)
class HeadingSearch:
    """The headings a wide search tries: the correlation's candidates and any suggested ones (the
    motion's hypotheses), merged within ±window, each searched ±window in ``step`` (every heading
    where neither the normals nor a suggestion gives one)."""

    bin_rad: float
    smooth_rad: float
    count: int
    window_rad: float
    step_rad: float

    @classmethod
    def from_config(cls, cfg: FrontEndConfig) -> "HeadingSearch":
        return cls(np.radians(cfg.histogram_bin_deg), np.radians(cfg.histogram_smooth_deg), cfg.rotation_candidates,
                   np.radians(cfg.rotation_window_deg), np.radians(cfg.angle_step_deg))

    def headings(self, scan_normals: np.ndarray, map_normals: np.ndarray, suggested=()) -> np.ndarray:
        """The headings (A,) to search, centres first, each with its window of offsets."""
        found = rotation_candidates(scan_normals, map_normals, self.bin_rad, self.smooth_rad, self.count)
        centres = merge_headings(np.concatenate([np.asarray(suggested, dtype=np.float64), found]), self.window_rad)
        if len(centres) == 0:
            centres = np.arange(0.0, 2 * np.pi, 2 * self.window_rad)
        return (centres[:, None] + window_angles(self.window_rad, self.step_rad)[None, :]).ravel()
