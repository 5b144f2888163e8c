"""A triangle mesh with a material per face: a scene in 3D (:mod:`radioslam.scene.extrude`,
:mod:`radioslam.scene.mitsuba`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Mesh:
    """Triangles (F, 3) into vertices (V, 3), each face's material (F,) (index into ``material_names``)."""

    vertices: np.ndarray
    faces: np.ndarray
    face_material: np.ndarray
    material_names: tuple[str, ...]

    def area(self) -> np.ndarray:
        """Area (F,) of each face."""
        a, b, c = (self.vertices[self.faces[:, k]] for k in range(3))
        return 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)

    def of_material(self, m: int) -> "Mesh":
        """The faces of material m alone, with only the vertices they use."""
        faces = self.faces[self.face_material == m]
        used, inverse = np.unique(faces, return_inverse=True)
        return Mesh(self.vertices[used], inverse.reshape(faces.shape), np.full(len(faces), m), self.material_names)

    @classmethod
    def box(cls, low: tuple[float, float, float], high: tuple[float, float, float], material: int,
            material_names: tuple[str, ...]) -> "Mesh":
        """An axis-aligned box from corner ``low`` to ``high``: 8 vertices, 12 triangles, normals outwards."""
        (x0, y0, z0), (x1, y1, z1) = low, high
        vertices = np.array([[x, y, z] for z in (z0, z1) for y in (y0, y1) for x in (x0, x1)], dtype=np.float64)
        quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
        faces = np.array([[q[0], q[1], q[2]] for q in quads] + [[q[0], q[2], q[3]] for q in quads], dtype=np.int64)
        return cls(vertices, faces, np.full(len(faces), material), material_names)

    @classmethod
    def join(cls, meshes: list["Mesh"]) -> "Mesh":
        """One mesh of several that share their material names."""
        offsets = np.cumsum([0] + [len(m.vertices) for m in meshes[:-1]])
        return cls(np.concatenate([m.vertices for m in meshes]),
                   np.concatenate([m.faces + o for m, o in zip(meshes, offsets)]),
                   np.concatenate([m.face_material for m in meshes]), meshes[0].material_names)
