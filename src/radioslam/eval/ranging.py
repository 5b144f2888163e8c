"""Ranging error of specular echoes against the true walls (issue #14's sweep plots: ranging RMSE
against the Cramér–Rao bound, :mod:`radioslam.eval.crb`).

A wall seen off a specular arc echoes from the foot of the perpendicular from the terminal onto it:
the true two-way delay is 2·d⊥/c (paper eq. (7) with the specular point). A scan point at range r
whose beam looks within ``tolerance_rad`` of that foot (the evaluation uses the beam's half-power
half-width: farther off, diffuse scattering at d⊥/cos α competes), on the wall segment itself, is an
echo of that wall; its ranging error is r − d⊥ (the wall with the least |r − d⊥| where several qualify, and
none beyond ``gate_m``: a multipath ghost or a scatterer is not a ranging error). Position errors of
the pose do not enter: the terminal stands at its true pose.
"""

from __future__ import annotations

import numpy as np

from radioslam.scene.geometry import cross2


def specular_range_errors(pose: np.ndarray, range_m: np.ndarray, angle_rad: np.ndarray, segments: np.ndarray,
                          tolerance_rad: float, gate_m: float = 0.5) -> np.ndarray:
    """r − d⊥ (M,) of the points (range, terminal-frame bearing) of one scan taken at the true ``pose``
    that echo a wall of ``segments`` (S, 2, 2) specularly; the others are left out."""
    if len(range_m) == 0 or len(segments) == 0:
        return np.zeros(0)
    a, e = segments[:, 0], segments[:, 1] - segments[:, 0]
    t = np.einsum("sk,sk->s", pose[:2] - a, e) / np.einsum("sk,sk->s", e, e)
    foot = a + t[:, None] * e  # (S, 2) the specular point on each wall's line
    offset = foot - pose[:2]
    distance = np.linalg.norm(offset, axis=1)
    facing = (t >= 0.0) & (t <= 1.0) & (np.abs(cross2(pose[:2] - a, e)) > 0)
    bearing = np.arctan2(offset[:, 1], offset[:, 0])  # (S,) world bearing of each foot
    look = pose[2] + np.asarray(angle_rad)[:, None] - bearing[None]  # (P, S)
    within = facing[None] & (np.abs(np.angle(np.exp(1j * look))) <= tolerance_rad)
    error = np.where(within, np.asarray(range_m)[:, None] - distance[None], np.inf)
    best = np.take_along_axis(error, np.argmin(np.abs(error), axis=1)[:, None], axis=1)[:, 0]
    return best[np.abs(best) <= gate_m]


def beam_half_width_rad(elements: int) -> float:
    """Half the half-power beamwidth of a broadside ULA of ``elements`` at half-wavelength spacing
    (0.886·λ/(N·d), Van Trees, *Optimum Array Processing*, §2.4)."""
    return 0.5 * 0.886 * 2.0 / elements


def robust_rmse(errors: np.ndarray) -> tuple[float | None, int]:
    """The RMS of the errors within 3 robust standard deviations (1.4826 × the median absolute
    deviation) of their median, and how many those are: an echo of something else within the beam (an
    obstacle before the wall, a corner) is not a ranging error of the wall's. None where there is none."""
    errors = np.asarray(errors, dtype=np.float64)
    if len(errors) == 0:
        return None, 0
    centre = np.median(errors)
    spread = 1.4826 * np.median(np.abs(errors - centre))
    kept = errors[np.abs(errors - centre) <= 3.0 * spread] if spread > 0 else errors
    return float(np.sqrt(np.mean(kept**2))), int(len(kept))
