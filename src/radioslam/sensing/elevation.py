"""A detection's elevation from the elevation rows' responses at its range (issue #16): amplitude
comparison across the beams of one (orientation, azimuth index) pair, a matched filter in beam space.

A scatterer at direction cosine u_z (sin ε) puts on elevation row j an amplitude proportional to that
row's two-way vertical factor g_j(u_z) (:meth:`~radioslam.antenna.codebook.BeamSet.vertical_gain`). With
the magnitudes m_j = |F_j(τ)| of every row's range profile at the detection's delay τ, the estimate is

    û_z = argmax_u Σ_j m_j·g_j(u) / ‖g(u)‖,

on a grid of u 1/1000 apart within one row step of the detecting beam's own u_z (the echo is in its
main lobe: a floor and a ceiling at the same slant range echo alike on rows −j and +j, which a single
scatterer's fit over every row cannot tell apart), and from half a step below the lowest beam to half a
step above the highest (beyond them the shape of g no longer tells u). A detection makes a point only
where its row's magnitude is within 6 dB of the strongest row's at that delay (adjacent rows cross at
−3.9 dB), and where the window's best fit reaches ``SIDELOBE_FIT_RATIO`` of the best fit at any
elevation (|u| ≤ 0.99): otherwise every row sees the echo through a sidelobe, as they see a floor and a
ceiling 1.5 m away, at ±60° and the same slant range (on the extruded paper-cnv these gave the
horizontal row 11 off-wall points a scan, at 1.7–1.9 m, fit 0.52–0.6 inside the window against
0.99 at u ≈ ±0.93; docs/notes.md, session 26). The beam's own u_z alone would put a floor echo,
strongest at the steep lower edge of a low beam's footprint, at that beam's centre: 0.66 m high on
average on the extruded paper-cnv (7 rows); see docs/notes.md, session 24.
"""

from __future__ import annotations

import numpy as np

from radioslam.antenna.codebook import vertical_factors
from radioslam.sensing.profile import RangeSpectrum

GRID_STEP = 1e-3
U_LIMIT = 0.99  # the fit's grid over u_z = sin ε: ±82°
# a detection's fit within its window must reach this fraction of the best fit at any elevation
SIDELOBE_FIT_RATIO = 0.8
MAIN_LOBE_AMPLITUDE = 10 ** (-6 / 20)  # a detecting row within 6 dB of the strongest row keeps the echo


def sibling_rows(orientation: np.ndarray, beam_index: np.ndarray, elevation_index: np.ndarray,
                 rows_j: np.ndarray) -> np.ndarray:
    """(B, J) for each beam the rows of the same orientation and azimuth index on each elevation row j
    of ``rows_j`` (a row missing from the capture: the beam itself)."""
    i_values = np.unique(beam_index)
    table = np.full((int(orientation.max()) + 1, len(rows_j), len(i_values)), -1, dtype=np.int64)
    ipos = np.searchsorted(i_values, beam_index)
    table[orientation, np.searchsorted(rows_j, elevation_index), ipos] = np.arange(len(beam_index))
    siblings = table[orientation, :, ipos]  # (B, J)
    return np.where(siblings < 0, np.arange(len(beam_index))[:, None], siblings)


def detection_elevations(spec: RangeSpectrum, window_offset: np.ndarray, lag: np.ndarray, valid: np.ndarray,
                         orientation: np.ndarray, beam_index: np.ndarray, elevation_index: np.ndarray,
                         n_elements: int, bits: int) -> tuple[np.ndarray, np.ndarray]:
    """û_z (B, M) of every detection (NaN where not valid), each row's profile at the detection's delay
    (its own window offset) matched against the rows' patterns; and whether the detecting row sees the echo
    in its main lobe (within 6 dB of the strongest row, (B, M))."""
    rows_j = np.unique(elevation_index)
    siblings = sibling_rows(orientation, beam_index, elevation_index, rows_j)  # (B, J)
    delay = window_offset[:, None] + np.where(valid, lag, 0.0)  # (B, M) in samples from the window start
    lags = delay[:, None, :] - window_offset[siblings][:, :, None]  # (B, J, M) lag on each sibling
    b, j, m = lags.shape
    magnitude = np.abs(spec.with_derivatives(lags.reshape(b * j, m), rows=siblings.ravel(), order=0)[0])
    magnitude = magnitude.reshape(b, j, m).transpose(0, 2, 1)  # (B, M, J)
    step = 2.0 * (rows_j[1] - rows_j[0]) / 2**bits if len(rows_j) > 1 else 1.0
    lo, hi = 2.0 * rows_j[0] / 2**bits - step / 2, 2.0 * rows_j[-1] / 2**bits + step / 2
    u = np.arange(-U_LIMIT, U_LIMIT + GRID_STEP / 2, GRID_STEP)  # every elevation, for the sidelobe test
    pattern = vertical_factors(n_elements, bits, rows_j, u) ** 2  # g_j(u) (J, U), two way
    pattern /= np.linalg.norm(pattern, axis=0, keepdims=True)
    score = magnitude @ pattern  # (B, M, U)
    anywhere = score.max(axis=-1)  # the best single scatterer at any elevation
    own = 2.0 * elevation_index / 2**bits  # the detecting beam's u_z: the echo lies in its main lobe
    window = (np.abs(u[None, :] - own[:, None]) <= step) & (u >= lo) & (u <= hi)  # (B, U)
    score[~window[:, None, :]] = -np.inf
    best = np.argmax(score, axis=-1)  # (B, M)
    estimate = np.where(valid, u[best], np.nan)
    # an echo that one scatterer outside the window explains much better came through a sidelobe
    in_main_lobe = score.max(axis=-1) >= SIDELOBE_FIT_RATIO * anywhere
    # a far row sees a strong echo through a sidelobe (the per-row point threshold would keep it there, its
    # row's strongest): a point only where the detecting row is within 6 dB of the strongest row at that delay
    own_row = np.searchsorted(rows_j, elevation_index)  # (B,)
    own_magnitude = np.take_along_axis(magnitude, np.broadcast_to(own_row[:, None, None], (b, m, 1)), axis=-1)[..., 0]
    nearest = valid & (own_magnitude >= MAIN_LOBE_AMPLITUDE * magnitude.max(axis=-1)) & in_main_lobe
    return estimate, nearest
