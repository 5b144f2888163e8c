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
