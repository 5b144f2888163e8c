"""The runtime scene: wall segments as arrays, their materials, the poses and the radio."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from pydantic import ValidationError

from radioslam.config import RadioConfig
from radioslam.nr.frame import FrameSchedule
from radioslam.nr.numerology import NumerologyError
from radioslam.scene.errors import SceneError, validation_error
from radioslam.scene.geometry import point_segment_distance
from radioslam.scene.materials import BUILTIN_BY_ITU, BUILTIN_MATERIALS, Material
from radioslam.scene.mitsuba import horizontal_slice, read_mitsuba
from radioslam.scene.schema import SceneSpec
from radioslam.scene.trajectory import trajectory_poses

MIN_WALL_CLEARANCE_M = 0.2


@dataclass(frozen=True)
class Scene:
    """A validated scene. ``spec`` keeps the file form for writing ``scene.yaml``."""

    spec: SceneSpec
    segments: np.ndarray  # (S, 2, 2)
    segment_wall: np.ndarray  # (S,) index of the polyline in spec.walls
    segment_material: np.ndarray  # (S,) index into materials
    materials: tuple[Material, ...]
    material_names: tuple[str, ...]
    poses: np.ndarray  # (P, 3)

    @property
    def name(self) -> str:
        return self.spec.name

    @property
    def radio(self) -> RadioConfig:
        return self.spec.radio

    def material_array(self, attribute: str) -> np.ndarray:
        """Per-segment values of a material attribute, e.g. ``transmission``."""
        values = np.array([getattr(m, attribute) for m in self.materials])
        return values[self.segment_material]

    def with_radio(self, **overrides: object) -> "Scene":
        """The same scene with radio fields replaced (``None`` values are ignored)."""
        changes = {k: v for k, v in overrides.items() if v is not None}
        try:
            radio = RadioConfig(**{**self.radio.model_dump(), **changes})
        except ValidationError as exc:
            raise validation_error(exc, "(command line)", ("radio",)) from None
        return build_scene(self.spec.model_copy(update={"radio": radio}))


def build_scene(spec: SceneSpec, source: str | None = None) -> Scene:
    """Turn a schema-valid spec into arrays, checking the radio schedule, materials, segments
    and clearances."""
    try:
        FrameSchedule.from_config(spec.radio)
    except NumerologyError as exc:
        raise SceneError(str(exc), file=source, field="radio") from None
    materials = dict(BUILTIN_MATERIALS)
    materials.update({name: Material(**m.model_dump()) for name, m in spec.materials.items()})
    if spec.mitsuba is not None:
        return _mitsuba_scene(spec, materials, source)
    names = tuple(materials)
    segments, wall_of, material_of = [], [], []
    for w, wall in enumerate(spec.walls):
        if wall.material not in materials:
            raise SceneError(f"unknown material '{wall.material}' (known: {', '.join(names)})",
                             file=source, field=f"walls[{w}].material")
        pts = np.asarray(wall.points, dtype=np.float64)
        if np.any(np.linalg.norm(np.diff(pts, axis=0), axis=1) < 1e-9):
            raise SceneError("two consecutive points coincide (zero-length segment)",
                             file=source, field=f"walls[{w}].points")
        segments.append(np.stack([pts[:-1], pts[1:]], axis=1))
        wall_of += [w] * (len(pts) - 1)
        material_of += [names.index(wall.material)] * (len(pts) - 1)
    seg = np.concatenate(segments)
    _check_extrusion(spec, names, source)
    return _with_poses(spec, seg, np.array(wall_of), np.array(material_of), materials, names, source)


def _mitsuba_scene(spec: SceneSpec, materials: dict[str, Material], source: str | None) -> Scene:
    """A scene of a Mitsuba XML file (resolved against the scene file's folder and kept absolute, so that
    a run's scene.yaml finds it): its walls are the mesh's slice at the terminal's height, each bsdf a
    material of its ITU class (a built-in material of that class lends the 2D caster its parameters)."""
    path = Path(spec.mitsuba)
    if not path.is_absolute() and source is not None and Path(source).exists():
        path = Path(source).resolve().parent / path
    mesh, itu = read_mitsuba(path)
    spec = spec.model_copy(update={"mitsuba": str(path.resolve())})
    segments, face_material = horizontal_slice(mesh, spec.radio.height_m)
    if not len(segments):
        raise SceneError(f"no wall crosses the terminal's height {spec.radio.height_m:g} m", file=str(path),
                         field="radio.height_m")
    for name, (cls, thickness) in itu.items():
        model = BUILTIN_BY_ITU.get(cls, BUILTIN_MATERIALS["concrete"])  # the caster refuses a class it lacks
        materials[name] = Material(model.reflectivity, model.scattering, model.directivity, model.transmission, cls,
                                   thickness)
    names = tuple(materials)
    material_of = np.array([names.index(mesh.material_names[m]) for m in face_material])
    return _with_poses(spec, segments, np.arange(len(segments)), material_of, materials, names, source)


def _with_poses(spec, seg, wall_of, material_of, materials, names, source) -> Scene:
    """The scene of these segments, once every pose keeps its distance from them."""
    poses = trajectory_poses(spec.trajectory)
    dist = point_segment_distance(poses[:, :2], seg)
    near = np.argwhere(dist < MIN_WALL_CLEARANCE_M)
    if len(near):
        p, s = near[0]
        where = "trajectory.poses" if spec.trajectory.poses is not None else "trajectory.circle"
        wall = f"walls[{wall_of[s]}]" if spec.walls is not None else f"the mitsuba scene's wall {s}"
        raise SceneError(
            f"pose {p} at ({poses[p, 0]:.3f}, {poses[p, 1]:.3f}) is {dist[p, s]:.3f} m from "
            f"{wall}, closer than {MIN_WALL_CLEARANCE_M} m",
            file=source, field=f"{where}[{p}]" if spec.trajectory.poses is not None else where)
    return Scene(spec, seg, np.asarray(wall_of), np.asarray(material_of), tuple(materials[n] for n in names), names,
                 poses)


def _check_extrusion(spec: SceneSpec, names: tuple[str, ...], source: str | None) -> None:
    """An extruded scene's floor and ceiling materials are known, and both arrays lie between them."""
    if spec.extrude is None:
        return
    for key in ("floor", "ceiling"):
        material = getattr(spec.extrude, key)
        if material is not None and material not in names:
            raise SceneError(f"unknown material '{material}' (known: {', '.join(names)})", file=source,
                             field=f"extrude.{key}")
    radio, height = spec.radio, spec.extrude.height_m
    low, high = radio.height_m - radio.array_baseline_m / 2, radio.height_m + radio.array_baseline_m / 2
    if not 0.0 < low <= high < height:
        raise SceneError(f"the arrays span {low:.3f}–{high:.3f} m, not inside the walls' 0–{height:g} m",
                         file=source, field="radio.height_m")
