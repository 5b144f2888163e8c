"""The built-in caster in 2.5D (issue #16): diffuse echoes over azimuth and elevation, for a radio that
sweeps elevation beams.

The scene stays what the 2D caster sees, vertical walls, here of the height ``extrude.height_m`` (none:
unbounded), with the extrusion's floor (z = 0) and ceiling (z = height) when named. From the terminal
at height h₀ a fan of rays, δ apart in azimuth φ and in elevation ε (``radio.ray_spacing_3d_deg``),
leaves the arrays' centre. The azimuth rays are cast in 2D (:func:`~radioslam.scene.raycast.cast_rays`,
transmission through walls included); a ray at elevation ε reaches the wall hit at horizontal distance
ρ if its height h₀ + ρ·tan ε lies on the wall (0 … height), and the floor (ε < 0) or ceiling (ε > 0)
at ρ_f = |Δz|/tan|ε| if it meets no opaque wall before. Each hit is one path of slant range R:

    b = λ/(4π·2R) · Γ·S · √(L(ψ)·δφ) · √(δε/W) · ΠT² · e^{−j2π f_c τ}

with L the material's backscatter lobe (:mod:`radioslam.scene.materials`) at the 3D incidence ψ
(cos ψ = cos ε·cos ψ_h on a wall, sin|ε| on the floor or ceiling) and W = Σ_k c(ε_k)⁴·δε, c the 8 rows'
broadside factor (:meth:`~radioslam.antenna.codebook.BeamSet.vertical_gain` of the horizontal beam).
The last factor keeps the flat caster's calibration: an unbounded wall returns on the horizontal beam
the power the 2D caster's ray gives it. τ is the bistatic path from the TX array (h₀ + b/2) to the
point and back to the RX array (h₀ − b/2). Specular returns stay the 2D caster's, horizontal (a
monostatic terminal sees the floor's and the ceiling's at ±90°, where its elements do not).
"""

from __future__ import annotations

import numpy as np

from radioslam.antenna.codebook import BeamSet
from radioslam.config import SPEED_OF_LIGHT, RadioConfig
from radioslam.scene.model import Scene
from radioslam.scene.raycast import cast_rays

FLOOR_SEGMENT, CEILING_SEGMENT = -2, -3  # EchoPaths.segment of a floor or ceiling echo (−1: leakage)


def elevation_fan(radio: RadioConfig) -> tuple[np.ndarray, float]:
    """Elevations ε_k (E,) of the fan, strictly inside (−π/2, π/2), and the normalization W."""
    step = np.radians(radio.ray_spacing_3d_deg)
    count = int(round(np.pi / step))
    elevation = -np.pi / 2 + (np.arange(count) + 0.5) * (np.pi / count)
    flat = BeamSet(radio.array_elements, radio.codebook_bits, 0, 1)  # the one horizontal beam
    weight = float(np.sum(flat.vertical_gain(elevation)[0] ** 2) * (np.pi / count))
    return elevation, weight


def bistatic_slant_delay(horizontal_m: np.ndarray, dz_m: np.ndarray, baseline_m: float) -> np.ndarray:
    """τ of a point ρ away horizontally and Δz above the arrays' centre: TX at +b/2, RX at −b/2."""
    up, down = np.hypot(horizontal_m, dz_m - baseline_m / 2), np.hypot(horizontal_m, dz_m + baseline_m / 2)
    return (up + down) / SPEED_OF_LIGHT


def elevated_diffuse_paths(scene: Scene, pose: np.ndarray, radio: RadioConfig):
    """(delay, amplitude, azimuth, segment, point (P, 2), elevation) of the 2.5D fan's echoes (terminal-frame
    azimuth and elevation; the point's world x, y, its height is h₀ + ρ·tan ε)."""
    step = np.radians(radio.ray_spacing_3d_deg)
    n = int(round(2 * np.pi / step))
    azimuth = -np.pi + (np.arange(n) + 0.5) * (2 * np.pi / n)
    elevation, weight = elevation_fan(radio)
    d_el = np.pi / len(elevation)
    hits = cast_rays(pose[:2], pose[2] + azimuth, scene.segments, scene.material_array("transmission"),
                     radio.max_hits, radio.max_range_m)
    h0, extrude = radio.height_m, scene.spec.extrude
    top = np.inf if extrude is None else extrude.height_m
    tan_el = np.tan(elevation)  # (E,)
    rho = hits.distance  # (R, H), inf where unused
    with np.errstate(invalid="ignore"):
        z = h0 + rho[:, :, None] * tan_el  # (R, H, E) height of each ray where it meets each wall
    on_wall = hits.valid[:, :, None] & (z >= 0.0) & (z <= top)
    seg = np.where(hits.valid, hits.segment, 0)
    t_wall = scene.material_array("transmission")[seg] ** 2 * hits.valid  # two-way T² of each wall hit
    parts = [_wall_echoes(scene, hits, on_wall, elevation, seg)]
    for name, dz, sign, code in ((None if extrude is None else extrude.floor, -h0, -1.0, FLOOR_SEGMENT),
                                 (None if extrude is None else extrude.ceiling, top - h0, 1.0, CEILING_SEGMENT)):
        if name is not None:
            parts.append(_plane_echoes(scene, hits, t_wall, elevation, dz, sign, code, name, radio.max_range_m))
    ray, el, r_h, seg_of, gamma_s, lobe, trans = (np.concatenate(x) for x in zip(*parts))
    slant = r_h / np.cos(elevation[el])
    near = slant <= radio.max_range_m  # steep rays reach an unbounded wall far up
    ray, el, r_h, seg_of, gamma_s, lobe, trans, slant = (x[near] for x in (ray, el, r_h, seg_of, gamma_s, lobe,
                                                                             trans, slant))
    dz = r_h * tan_el[el]
    tau = bistatic_slant_delay(r_h, dz, radio.array_baseline_m)
    spread = radio.wavelength_m / (4.0 * np.pi * 2.0 * slant)
    amp = spread * gamma_s * np.sqrt(lobe * (2 * np.pi / n)) * np.sqrt(d_el / weight) * trans
    amp = amp * np.exp(-2j * np.pi * radio.carrier_hz * tau)
    world = hits.angle[ray]
    point = pose[:2] + r_h[:, None] * np.stack([np.cos(world), np.sin(world)], axis=-1)
    return tau, amp, azimuth[ray], seg_of, point, elevation[el]


def _lobes(scene: Scene, material: np.ndarray, incidence: np.ndarray) -> np.ndarray:
    """L(ψ) of each echo's material (one call per material of the scene)."""
    out = np.zeros(len(material))
    for m in np.unique(material):
        sel = material == m
        out[sel] = scene.materials[m].backscatter_lobe(incidence[sel])
    return out


def _wall_echoes(scene: Scene, hits, on_wall: np.ndarray, elevation: np.ndarray, seg: np.ndarray):
    ray, h, el = np.nonzero(on_wall)
    segment = seg[ray, h]
    cos_psi = np.clip(hits.cos_incidence[ray, h], 0, 1) * np.cos(elevation[el])
    material = scene.segment_material[segment]
    gamma_s = scene.material_array("reflectivity")[segment] * scene.material_array("scattering")[segment]
    lobe = _lobes(scene, material, np.arccos(cos_psi))
    return ray, el, hits.distance[ray, h], segment, gamma_s, lobe, hits.transmission[ray, h]


def _plane_echoes(scene: Scene, hits, t_wall: np.ndarray, elevation: np.ndarray, dz: float, sign: float,
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
