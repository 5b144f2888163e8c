"""A 2D scene as a 3D triangle mesh (issue #16): every wall segment a vertical rectangle from the floor
(z = 0) to ``extrude.height_m``, and the floor and ceiling, when named, rectangles over the walls'
bounding box. What a ray tracer of meshes takes (Sionna RT, built in memory by
:mod:`radioslam.sim.sionna_channel`).

Each rectangle is two triangles; a face's material is its wall's. Normals are left to the tracer
(walls reflect from either side).
"""

from __future__ import annotations

import numpy as np

from radioslam.scene.errors import SceneError
from radioslam.scene.mesh import Mesh
from radioslam.scene.mitsuba import read_mitsuba
from radioslam.scene.model import Scene


def _rectangles(corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (4R, 3) and faces (2R, 3) of rectangles given by their corners (R, 4, 3) in order."""
    vertices = corners.reshape(-1, 3)
    base = 4 * np.arange(len(corners))[:, None]
    faces = np.concatenate([base + [0, 1, 2], base + [0, 2, 3]], axis=1).reshape(-1, 3)
    return vertices, faces


def extruded_mesh(scene: Scene) -> Mesh:
    """The scene's walls, floor and ceiling (``scene.spec.extrude``) as one mesh."""
    spec = scene.spec.extrude
    if spec is None:
        raise SceneError("a 3D channel needs the walls' height: add extrude: {height_m: ...}", field="extrude")
    height, seg = spec.height_m, scene.segments
    low, high = np.zeros((len(seg), 2, 1)), np.full((len(seg), 2, 1), height)
    # a, b at the floor, then b, a at the top
    walls = np.concatenate([np.concatenate([seg, low], axis=2), np.concatenate([seg[:, ::-1], high], axis=2)], axis=1)
    corners, materials = [walls], [scene.segment_material]
    (x0, y0), (x1, y1) = seg.reshape(-1, 2).min(axis=0), seg.reshape(-1, 2).max(axis=0)
    for name, z in ((spec.floor, 0.0), (spec.ceiling, height)):
        if name is not None:
            corners.append(np.array([[[x0, y0, z], [x1, y0, z], [x1, y1, z], [x0, y1, z]]]))
            materials.append(np.array([scene.material_names.index(name)]))
    vertices, faces = _rectangles(np.concatenate(corners))
    face_material = np.repeat(np.concatenate(materials), 2)
    return Mesh(vertices, faces, face_material, scene.material_names)


def scene_mesh(scene: Scene) -> Mesh | None:
    """The scene's true 3D surfaces: its Mitsuba mesh, its extrusion, or None for a 2D scene."""
    if scene.spec.mitsuba is not None:
        return read_mitsuba(scene.spec.mitsuba)[0]
    return None if scene.spec.extrude is None else extruded_mesh(scene)
