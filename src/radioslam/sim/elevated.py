"""The built-in caster in 2.5D (issue #16): diffuse echoes over azimuth and elevation, for a radio that
sweeps elevation beams.

The scene stays what the 2D caster sees, vertical walls, here of the height ``extrude.height_m`` (none:
unbounded), with the extrusion's floor (z = 0) and ceiling (z = height) when named. The terminal's
arrays are centred at height h₀.

**Walls, one path per wall column and elevation row.** The 2D caster's own rays (``ray_spacing_deg``,
the flat scan's) meet each wall at horizontal distance ρ: a vertical column of wall, seen by elevation
row j through its two-way vertical pattern c_j(ε)⁴ (:func:`~radioslam.antenna.codebook.vertical_factors`).
A diffuse wall's scattering elements add in power (Degli-Esposti's diffuse field has no coherent part),
so the column gives row j one path whose power is the row's integral over the column's visible
elevations [ε_lo, ε_hi] (the wall's foot and top, and ``max_range_m``):

    P_j = ∫ c_j(ε)⁴ · L(ψ(ε)) · cos²ε dε / W,     W = ∫ c_0(ε)⁴ dε   (over (−π/2, π/2))
    b_j = λ/(4π·2ρ) · Γ·S · √(δφ·P_j) · ΠT² · e^{−j2π f_c τ_j}

with L the material's backscatter lobe (:mod:`radioslam.scene.materials`) at the 3D incidence
cos ψ = cos ε·cos ψ_h and cos²ε = (ρ/R)² the slant range's extra spreading. The path lies at the
column's point at ε_j, the P_j-weighted centroid of the elevations, and its delay τ_j is the slant path
to it (TX at h₀ + b/2 → point → RX at h₀ − b/2). It reaches row j only (``EchoPaths.row``): its
vertical pattern is in P_j. For a wall seen symmetrically (its foot and top as far below and above the
arrays) the horizontal row's centroid is ε = 0 and W makes its path the flat caster's ray, in delay and
phase exactly and in power to the 3D lobe's tenth of a dB: the horizontal row is the flat scan's
channel (and nearly so for a wall from the floor up without a top: the centroid 10⁻⁷ rad up). The
integral is a quadrature on ``WALL_STEP_DEG``, each cell weighted by the part of it the wall covers, so a
column's power moves continuously with ρ. Two earlier forms, measured on paper-cnv (docs/notes.md,
session 26): elevation sampled by rays of their own (2° apart) made a column's rays add coherently near
ε = 0 by an amount that depended on the spacing, the horizontal row's diffuse echoes rose 4 dB against
its specular ones and the SLAM's ATE went from the flat scan's 0.01 m to 0.02–0.05 m with the spacing;
a delay averaged over the slant paths lay 16 mm beyond the flat ray's, its phase no longer added the
near-normal diffuse echoes to the specular one as the flat caster does, and the horizontal row kept 40 %
more points, most of them on oblique walls.

**Floor and ceiling, one path per ray of a fan.** Rays δ apart in azimuth and elevation
(``radio.ray_spacing_3d_deg``) reach the floor (ε < 0) or ceiling (ε > 0) at ρ_f = |Δz|/tan|ε| where
they meet no opaque wall first, each a path reaching every row through its vertical gain:

    b = λ/(4π·2R) · Γ·S · √(L(ψ)·δφ) · √(δε/W_δ) · ΠT² · e^{−j2π f_c τ},   cos ψ = sin|ε|,

W_δ the fan's own sum Σ c_0(ε_k)⁴ δε. Specular returns stay the 2D caster's, horizontal (a monostatic
terminal sees the floor's and the ceiling's at ±90°, where its elements do not).
"""

from __future__ import annotations

import numpy as np

from radioslam.antenna.codebook import ANY_ROW, BeamSet, vertical_factors
from radioslam.config import SPEED_OF_LIGHT, RadioConfig
from radioslam.scene.model import Scene
from radioslam.scene.raycast import RayHits, cast_fan

FLOOR_SEGMENT, CEILING_SEGMENT = -2, -3  # EchoPaths.segment of a floor or ceiling echo (−1: leakage)
WALL_STEP_DEG = 0.25  # the wall columns' elevation quadrature (a twentieth of a row's beam width)


def elevation_rows(radio: RadioConfig) -> np.ndarray:
    """The elevation codebook indices j of the radio's rows."""
    return np.asarray(BeamSet.from_config(radio).elevation_indices)


def elevation_fan(radio: RadioConfig) -> tuple[np.ndarray, float]:
    """Elevations ε_k (E,) of the floor and ceiling fan, strictly inside (−π/2, π/2), and its W_δ."""
    step = np.radians(radio.ray_spacing_3d_deg)
    count = int(round(np.pi / step))
    elevation = -np.pi / 2 + (np.arange(count) + 0.5) * (np.pi / count)
    weight = float(np.sum(_row_patterns(radio, np.zeros(1), elevation)[0]) * (np.pi / count))
    return elevation, weight


def bistatic_slant_delay(horizontal_m: np.ndarray, dz_m: np.ndarray, baseline_m: float) -> np.ndarray:
    """τ of a point ρ away horizontally and Δz above the arrays' centre: TX at +b/2, RX at −b/2."""
    up, down = np.hypot(horizontal_m, dz_m - baseline_m / 2), np.hypot(horizontal_m, dz_m + baseline_m / 2)
    return (up + down) / SPEED_OF_LIGHT


def elevated_diffuse_paths(scene: Scene, pose: np.ndarray, radio: RadioConfig):
    """(delay, amplitude, azimuth, segment, point (P, 2), elevation, row) of the 2.5D echoes: terminal-frame
    azimuth and elevation, the point's world x, y, and the elevation row j a wall column's path belongs to
    (``ANY_ROW`` for the floor's and ceiling's)."""
    parts = [wall_column_paths(scene, pose, radio)]
    extrude = scene.spec.extrude
    if extrude is not None and (extrude.floor is not None or extrude.ceiling is not None):
        plane = plane_paths(scene, pose, radio)
        parts.append((*plane, np.full(len(plane[0]), ANY_ROW, dtype=np.int64)))
    return tuple(np.concatenate(x) for x in zip(*parts))


def _row_patterns(radio: RadioConfig, rows: np.ndarray, elevation: np.ndarray) -> np.ndarray:
    """c_j(ε)⁴ (J, E): each row's two-way vertical power pattern."""
    return vertical_factors(radio.array_elements, radio.codebook_bits, rows, np.sin(elevation)) ** 4


def _visible_cells(lo: np.ndarray, hi: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """(C, E) the fraction of each quadrature cell [edges[e], edges[e+1]] inside [lo_c, hi_c]."""
    inside = np.minimum(hi[:, None], edges[None, 1:]) - np.maximum(lo[:, None], edges[None, :-1])
    return np.clip(inside / np.diff(edges)[None, :], 0.0, 1.0)


def _lobes(scene: Scene, material: np.ndarray, incidence: np.ndarray) -> np.ndarray:
    """L(ψ) of each echo's material (one call per material of the scene); ``incidence`` (C, ...)."""
    out = np.zeros(incidence.shape)
    for m in np.unique(material):
        sel = material == m
        out[sel] = scene.materials[m].backscatter_lobe(incidence[sel])
    return out


def wall_column_paths(scene: Scene, pose: np.ndarray, radio: RadioConfig):
    """Each wall column's path per elevation row (module docstring): (delay, amplitude, azimuth, segment,
    point, elevation, row)."""
    azimuth, hits = cast_fan(pose[:2], pose[2], np.radians(radio.ray_spacing_deg), scene.segments,
                             scene.material_array("transmission"), radio.max_hits, radio.max_range_m)
    step = 2 * np.pi / len(azimuth)
    ray, h = np.nonzero(hits.valid)
    rho, segment = hits.distance[ray, h], hits.segment[ray, h]
    # the quadrature over elevation, and the part of each cell the column covers (foot, top, max range)
    cells = int(round(180.0 / WALL_STEP_DEG))
    edges = np.linspace(-np.pi / 2, np.pi / 2, cells + 1)
    eps = 0.5 * (edges[1:] + edges[:-1])
    h0, extrude = radio.height_m, scene.spec.extrude
    top = np.inf if extrude is None else extrude.height_m
    reach = np.arccos(np.clip(rho / radio.max_range_m, 0.0, 1.0))  # slant ρ/cos ε ≤ max_range_m
    lo, hi = np.maximum(np.arctan2(-h0, rho), -reach), np.minimum(np.arctan2(top - h0, rho), reach)
    cover = _visible_cells(lo, hi, edges)  # (C, E)
    cos_psi = np.clip(hits.cos_incidence[ray, h], 0.0, 1.0)[:, None] * np.cos(eps)[None, :]
    lobe = _lobes(scene, scene.segment_material[segment], np.arccos(cos_psi))
    density = cover * lobe * np.cos(eps) ** 2 * np.diff(edges)  # (C, E)
    rows = elevation_rows(radio)
    pattern = _row_patterns(radio, rows, eps).T  # (E, J)
    unbounded = float(np.sum(_row_patterns(radio, np.zeros(1), eps)[0] * np.diff(edges)))  # W
    power = density @ pattern  # (C, J), times W
    col, row = np.nonzero(power > 0)
    elevation = ((density * eps) @ pattern)[col, row] / power[col, row]  # ε_j, the P_j-weighted centroid
    delay = bistatic_slant_delay(rho[col], rho[col] * np.tan(elevation), radio.array_baseline_m)
    gamma_s = scene.material_array("reflectivity")[segment] * scene.material_array("scattering")[segment]
    spread = radio.wavelength_m / (4.0 * np.pi * 2.0 * rho)
    amp = (spread * gamma_s * hits.transmission[ray, h])[col] * np.sqrt(step * power[col, row] / unbounded)
    world = hits.angle[ray][col]
    point = pose[:2] + rho[col, None] * np.stack([np.cos(world), np.sin(world)], axis=-1)
    return (delay, amp * np.exp(-2j * np.pi * radio.carrier_hz * delay), azimuth[ray][col], segment[col], point,
            elevation, rows[row].astype(np.int64))


def plane_paths(scene: Scene, pose: np.ndarray, radio: RadioConfig):
    """The floor's and ceiling's echoes of the fan (module docstring): (delay, amplitude, azimuth, segment,
    point, elevation)."""
    azimuth, hits = cast_fan(pose[:2], pose[2], np.radians(radio.ray_spacing_3d_deg), scene.segments,
                             scene.material_array("transmission"), radio.max_hits, radio.max_range_m)
    step = 2 * np.pi / len(azimuth)
    elevation, weight = elevation_fan(radio)
    d_el = np.pi / len(elevation)
    h0, extrude = radio.height_m, scene.spec.extrude
    seg = np.where(hits.valid, hits.segment, 0)
    t_wall = scene.material_array("transmission")[seg] ** 2 * hits.valid  # two-way T² of each wall hit
    parts = [_plane_echoes(scene, hits, t_wall, elevation, dz, sign, code, name, radio.max_range_m)
             for name, dz, sign, code in ((extrude.floor, -h0, -1.0, FLOOR_SEGMENT),
                                          (extrude.ceiling, extrude.height_m - h0, 1.0, CEILING_SEGMENT))
             if name is not None]
    ray, el, r_h, seg_of, gamma_s, lobe, trans = (np.concatenate(x) for x in zip(*parts))
    slant = r_h / np.cos(elevation[el])
    near = slant <= radio.max_range_m
    ray, el, r_h, seg_of, gamma_s, lobe, trans, slant = (x[near] for x in (ray, el, r_h, seg_of, gamma_s, lobe,
                                                                             trans, slant))
    tau = bistatic_slant_delay(r_h, r_h * np.tan(elevation[el]), radio.array_baseline_m)
    spread = radio.wavelength_m / (4.0 * np.pi * 2.0 * slant)
    amp = spread * gamma_s * np.sqrt(lobe * step) * np.sqrt(d_el / weight) * trans
    amp = amp * np.exp(-2j * np.pi * radio.carrier_hz * tau)
    world = hits.angle[ray]
    point = pose[:2] + r_h[:, None] * np.stack([np.cos(world), np.sin(world)], axis=-1)
    return tau, amp, azimuth[ray], seg_of, point, elevation[el]


def _plane_echoes(scene: Scene, hits: RayHits, t_wall: np.ndarray, elevation: np.ndarray, dz: float, sign: float,
                  code: int, name: str, max_range: float):
    """Echoes of the floor (sign −1, Δz < 0) or the ceiling (sign +1) where a ray meets it before an
    opaque wall: the walls crossed before it (ρ_h < ρ_f) give ΠT²."""
    going = np.flatnonzero(np.sign(elevation) == sign)
    rho_f = dz / np.tan(elevation[going])  # (E',) horizontal distance to the plane, > 0
    before = hits.distance[:, :, None] < rho_f  # (R, H, E') walls met first
    trans = np.prod(np.where(before, t_wall[:, :, None], 1.0), axis=1)  # (R, E')
    ok = (trans > 0) & (rho_f <= max_range)
    ray, k = np.nonzero(ok)
    material = scene.material_names.index(name)
    m = scene.materials[material]
    lobe = m.backscatter_lobe(np.arccos(np.abs(np.sin(elevation[going[k]]))))
    return (ray, going[k], rho_f[k], np.full(len(ray), code), np.full(len(ray), m.reflectivity * m.scattering),
            lobe, trans[ray, k])
