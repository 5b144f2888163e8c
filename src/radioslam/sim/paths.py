"""Echo paths of one pose: ray-traced diffuse echoes, specular returns, leakage.

Geometry: the TX/RX and the sensing RX arrays are stacked vertically, centres a
baseline b apart, so an echo from a wall point at horizontal distance r travels
2·√(r² + b²/4) (the TX/RX offset) and arrives after τ = 2√(r² + b²/4)/c.

Gains (complex amplitudes relative to the transmitted signal, before beam gain):
  diffuse, one per ray (angle step δθ) and hit (paper §IV-A: channel parameters
  from a dense set of rays):
      b = λ/(4π·2r) · Γ·S · √(L(ψ)·δθ) · ΠT² · e^{−j2π f_c τ}
      with the directive backscatter lobe L(ψ) of :mod:`radioslam.scene.materials`;
  specular, one per wall whose foot of perpendicular from the terminal lies on it
  (image source, normal incidence):
      b = λ/(4π·2r) · Γ·√(1 − S²) · ΠT² · e^{−j2π f_c τ};
  leakage, the full-duplex TX→RX coupling at τ = b/c (plus the radio's excess delay of the
      coupling path), amplitude 10^(−isolation/20) times the drift since calibration; its gain
      on each beam is the coupling between the two steered arrays (mean power 1 over the beams).
ΠT² is the two-way transmission through the walls crossed before the hit.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from enum import IntEnum

import numpy as np

from radioslam.antenna.codebook import ANY_ROW
from radioslam.config import SPEED_OF_LIGHT, RadioConfig, bistatic_delay_s
from radioslam.scene.model import Scene
from radioslam.scene.raycast import cast_fan, cast_rays
from radioslam.sim.elevated import elevated_diffuse_paths
from radioslam.sim.facets import facet_paths


class PathKind(IntEnum):
    DIFFUSE = 0
    SPECULAR = 1
    LEAKAGE = 2


@dataclass(frozen=True)
class EchoPaths:
    """Paths (P,) of one pose; ``angle`` is in the terminal frame (NaN for leakage)."""

    delay_s: np.ndarray  # over-the-air delay, hardware delay excluded
    amplitude: np.ndarray  # complex
    angle: np.ndarray
    kind: np.ndarray
    segment: np.ndarray  # −1 for leakage
    point: np.ndarray  # (P, 2) world coordinates of the echo point, NaN for leakage
    # (B, P) each path's gain on each beam where a backend computed it from its own element coefficients
    # (Sionna RT, :mod:`radioslam.sim.sionna_channel`); None: the codebook's gain at ``angle``
    beam_gain: np.ndarray | None = None
    # (P,) terminal-frame elevation of each path where a channel traces in 3D (NaN for leakage); None: all
    # horizontal, the 2D caster's flat paths
    elevation: np.ndarray | None = None
    # (P,) the one elevation row j a path reaches, its vertical pattern already in its amplitude (ANY_ROW:
    # every row, through the vertical gain); None: every path reaches every row
    row: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.delay_s)

    def by_delay(self) -> "EchoPaths":
        """The same paths, shortest delay first (ties keep their order); these when they are so already (a
        backend's beam gains are the largest array of a pose: not copied needlessly)."""
        if np.all(np.diff(self.delay_s) >= 0):
            return self
        order = np.argsort(self.delay_s, kind="stable")
        return EchoPaths(self.delay_s[order], self.amplitude[order], self.angle[order], self.kind[order],
                         self.segment[order], self.point[order],
                         None if self.beam_gain is None else self.beam_gain[:, order],
                         None if self.elevation is None else self.elevation[order],
                         None if self.row is None else self.row[order])


def _echo(r, gain_wo_range, radio: RadioConfig):
    tau = bistatic_delay_s(r, radio.array_baseline_m)
    spread = radio.wavelength_m / (4.0 * np.pi * 2.0 * r)
    return tau, spread * gain_wo_range * np.exp(-2j * np.pi * radio.carrier_hz * tau)


def diffuse_paths(scene: Scene, pose: np.ndarray, radio: RadioConfig):
    """One path per (ray, hit) of a full-circle fan of rays."""
    local, hits = cast_fan(pose[:2], pose[2], np.radians(radio.ray_spacing_deg), scene.segments,
                           scene.material_array("transmission"), radio.max_hits, radio.max_range_m)
    n = len(local)
    ray, h = np.nonzero(hits.valid)
    seg = hits.segment[ray, h]
    r = hits.distance[ray, h]
    mat = scene.segment_material[seg]
    lobe = np.array([m.backscatter_lobe(np.arccos(np.clip(hits.cos_incidence[ray, h], 0, 1)))
                     for m in scene.materials]) if len(scene.materials) else np.zeros((0, len(ray)))
    lobe = lobe[mat, np.arange(len(ray))]
    rs = scene.material_array("reflectivity")[seg] * scene.material_array("scattering")[seg]
    tau, amp = _echo(r, rs * np.sqrt(lobe * (2 * np.pi / n)) * hits.transmission[ray, h], radio)
    world = hits.angle[ray]
    point = pose[:2] + r[:, None] * np.stack([np.cos(world), np.sin(world)], axis=-1)
    return tau, amp, local[ray], seg, point


def specular_paths(scene: Scene, pose: np.ndarray, radio: RadioConfig):
    """Image-source returns from walls seen at normal incidence."""
    a, e = scene.segments[:, 0], scene.segments[:, 1] - scene.segments[:, 0]
    u = np.einsum("sk,sk->s", pose[:2] - a, e) / np.einsum("sk,sk->s", e, e)
    foot = a + u[:, None] * e
    vec = foot - pose[:2]
    r = np.linalg.norm(vec, axis=1)
    ok = (u > 0.0) & (u < 1.0) & (r > 1e-6)
    world = np.arctan2(vec[:, 1], vec[:, 0])
    hits = cast_rays(pose[:2], world, scene.segments, scene.material_array("transmission"),
                     radio.max_hits, radio.max_range_m)
    on_wall = (hits.segment == np.arange(len(r))[:, None]) & hits.valid
    trans = np.where(on_wall, hits.transmission, 0.0).sum(axis=1)
    ok &= on_wall.any(axis=1)
    s = np.flatnonzero(ok)
    gamma = scene.material_array("reflectivity")[s]
    coherent = np.sqrt(1.0 - scene.material_array("scattering")[s] ** 2)
    tau, amp = _echo(r[s], gamma * coherent * trans[s], radio)
    return tau, amp, np.angle(np.exp(1j * (world[s] - pose[2]))), s, foot[s]


def facet_specular(scene: Scene, pose: np.ndarray, radio: RadioConfig):
    """Specular returns as physical-optics facets (:mod:`radioslam.sim.facets`)."""
    r, gain, angle, segment, point = facet_paths(scene, pose, radio)
    tau, amp = _echo(r, gain, radio)
    return tau, amp, angle, segment, point


def echo_paths(scene: Scene, pose: np.ndarray, radio: RadioConfig | None = None,
               leakage: bool = True) -> EchoPaths:
    """Every echo path of the terminal at ``pose`` (x, y, θ)."""
    radio = radio or scene.radio
    pose = np.asarray(pose, dtype=np.float64)
    specular = facet_specular(scene, pose, radio) if radio.impairments.specular_facets else \
        specular_paths(scene, pose, radio)
    elevated = radio.elevation_beams > 1  # elevation beams: the 2.5D fan (:mod:`radioslam.sim.elevated`)
    diffuse = elevated_diffuse_paths(scene, pose, radio) if elevated else diffuse_paths(scene, pose, radio)
    parts = [diffuse[:5], specular]
    kinds = [np.full(len(p[0]), k) for p, k in zip(parts, (PathKind.DIFFUSE, PathKind.SPECULAR))]
    if leakage and np.isfinite(radio.isolation_db):
        parts.append(leakage_path(radio))
        kinds.append(np.array([PathKind.LEAKAGE]))
    paths = _joined(parts, kinds)
    if not elevated:
        return paths
    others = len(paths) - len(diffuse[0])  # the horizontal speculars (and the leakage, its elevation NaN)
    elevation = np.concatenate([diffuse[5], np.where(paths.kind[len(diffuse[0]):] == PathKind.LEAKAGE, np.nan, 0.0)])
    row = np.concatenate([diffuse[6], np.full(others, ANY_ROW, dtype=np.int64)])
    return replace(paths, elevation=elevation, row=row)


def leakage_path(radio: RadioConfig):
    """(delay, amplitude, angle, segment, point) of the TX→RX leakage."""
    return (np.array([radio.array_baseline_m / SPEED_OF_LIGHT + radio.leakage_excess_delay_s]),
            np.array([10.0 ** (-radio.isolation_db / 20.0) * radio.impairments.leakage_drift]), np.array([np.nan]),
            np.array([-1]), np.full((1, 2), np.nan))


def _joined(parts, kinds) -> EchoPaths:
    tau, amp, ang, seg, pt = (np.concatenate(x) for x in zip(*parts))
    return EchoPaths(tau, amp.astype(np.complex128), ang, np.concatenate(kinds).astype(np.int8), seg, pt)


def leakage_paths(radio: RadioConfig) -> EchoPaths:
    """The leakage alone: a capture with nothing in range, what its calibration measures."""
    return _joined([leakage_path(radio)], [np.array([PathKind.LEAKAGE])])
