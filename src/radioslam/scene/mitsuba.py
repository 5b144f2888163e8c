"""A Mitsuba 3 XML scene (Sionna RT's format, what its Blender add-on exports) as a triangle mesh, and
its horizontal slice at the terminal's height: the 2D walls the SLAM's map is judged against
(issue #16: ``mitsuba: FILE.xml`` in place of ``walls:``).

Read: ``<shape type="ply">`` meshes (``<string name="filename">``, relative to the XML file) with a
``<ref>`` to (or a nested) radio material as Sionna RT reads one: ``<bsdf type="itu-radio-material">``
with ``<string name="type">`` its ITU-R P.2040 class and ``<float name="thickness">``, or any bsdf whose
id is ``mat-itu_CLASS`` or ``itu_CLASS`` (Sionna's Blender add-on); ``<transform>`` and ``<default>``
substitutions are refused (the exporter writes neither). The slice cuts every triangle crossing
z = h into one segment.
"""

from __future__ import annotations

import xml.etree.ElementTree as ElementTree
from pathlib import Path

import numpy as np
from plyfile import PlyData, PlyElement, PlyParseError

from radioslam.scene.errors import SceneError
from radioslam.scene.materials import ItuMaterial
from radioslam.scene.mesh import Mesh

MAX_XML_BYTES = 4 << 20
MAX_FACES = 2_000_000


def _itu_material(bsdf, path: str) -> tuple[ItuMaterial, float] | None:
    """The ITU class and thickness of a bsdf as Sionna RT reads it: ``type="itu-radio-material"`` with a
    ``type`` string, or any bsdf (Blender's ``twosided`` around its look) whose id, past an optional
    ``mat-``, starts with ``itu_`` (the class: the rest of the id, or the ``type`` string); None for
    another bsdf."""
    name = bsdf.get("id") or ""
    name = name[4:] if name.startswith("mat-") else name
    named = name.startswith(("itu_", "itu-"))
    if bsdf.get("type") != "itu-radio-material" and not named:
        return None
    values = {e.get("name"): e.get("value") for e in bsdf if e.tag in ("string", "float")}
    kind = values.get("type", name[4:] if named else None)
    try:
        itu = ItuMaterial(kind)
    except ValueError:
        raise SceneError(f"unknown ITU material type {kind!r}", file=path,
                         field=f"bsdf[{bsdf.get('id')}].type") from None
    return itu, float(values.get("thickness", 0.1))


def _itu_materials(root, path: str) -> dict[str, tuple[ItuMaterial, float]]:
    """Each outermost bsdf's id (top level, or inside a shape: then named after the shape) and its
    ITU class and thickness."""
    out = {}
    for bsdf in root.findall("./bsdf"):
        material = _itu_material(bsdf, path)
        if material is not None and bsdf.get("id"):
            out[bsdf.get("id")] = material
    for shape in root.iter("shape"):
        inner = shape.find("bsdf")
        if inner is not None and (material := _itu_material(inner, path)) is not None:
            out[inner.get("id") or f"shape-{shape.get('id', '?')}"] = material
    return out


def read_mitsuba(path: str | Path) -> tuple[Mesh, dict[str, tuple[ItuMaterial, float]]]:
    """The mesh of every ply shape in the XML scene at ``path`` (faces' materials: bsdf ids) and each
    material's ITU class and thickness."""
    path = Path(path)
    where = str(path)
    if not path.is_file():
        raise SceneError("no such file (the mitsuba: scene)", file=where, field="mitsuba")
    if path.stat().st_size > MAX_XML_BYTES:
        raise SceneError(f"larger than {MAX_XML_BYTES >> 20} MiB", file=where, field="mitsuba")
    try:
        root = ElementTree.parse(path).getroot()
    except ElementTree.ParseError as exc:
        raise SceneError(f"not XML: {exc}", file=where, field="mitsuba") from None
    if root.find(".//default") is not None or root.find(".//transform") is not None:
        raise SceneError("<default> and <transform> are not supported (export with them applied)", file=where,
                         field="mitsuba")
    materials = _itu_materials(root, where)
    names = tuple(materials)
    vertices, faces, face_material, offset = [], [], [], 0
    for shape in root.iter("shape"):
        sid = shape.get("id", "?")
        if shape.get("type") != "ply":
            raise SceneError(f"shape type {shape.get('type')!r}: only ply meshes are read", file=where,
                             field=f"shape[{sid}]")
        filename = next((e.get("value") for e in shape.findall("string") if e.get("name") == "filename"), None)
        ref, inner = shape.find("ref"), shape.find("bsdf")
        material = ref.get("id") if ref is not None else \
            (inner.get("id") or f"shape-{sid}") if inner is not None else None
        if filename is None or material not in materials:
            raise SceneError("needs a filename and an ITU radio material (a bsdf of type itu-radio-material, or "
                             "one named itu_CLASS)", file=where, field=f"shape[{sid}]")
        v, f = _read_ply_mesh(path.parent / filename)
        vertices.append(v), faces.append(f + offset), face_material.append(np.full(len(f), names.index(material)))
        offset += len(v)
    if not faces or sum(len(f) for f in faces) > MAX_FACES:
        raise SceneError(f"needs 1 to {MAX_FACES:,} triangles", file=where, field="mitsuba")
    return Mesh(np.concatenate(vertices), np.concatenate(faces), np.concatenate(face_material), names), materials


def _read_ply_mesh(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (V, 3) and triangles (F, 3) of a PLY mesh (polygons fanned into triangles)."""
    try:
        ply = PlyData.read(str(path))
        vertex = ply["vertex"]
        v = np.stack([np.asarray(vertex[k], dtype=np.float64) for k in ("x", "y", "z")], axis=1)
        polygons = ply["face"]["vertex_indices"]
    except (OSError, PlyParseError, KeyError, ValueError) as exc:
        raise SceneError(f"not a PLY mesh: {exc}", file=str(path), field="(mesh)") from None
    triangles = [np.stack([np.full(len(p) - 2, p[0]), p[1:-1], p[2:]], axis=1) for p in polygons if len(p) >= 3]
    f = np.concatenate(triangles).astype(np.int64) if triangles else np.zeros((0, 3), np.int64)
    if not np.all(np.isfinite(v)) or (len(f) and (f.min() < 0 or f.max() >= len(v))):
        raise SceneError("vertex coordinates must be finite and faces index existing vertices", file=str(path),
                         field="(mesh)")
    return v, f


def horizontal_slice(mesh: Mesh, height: float) -> tuple[np.ndarray, np.ndarray]:
    """Segments (S, 2, 2) where the triangles cross z = ``height``, and each one's material (S,)."""
    z = mesh.vertices[mesh.faces, 2] - height  # (F, 3)
    above = z > 0
    crossing = np.flatnonzero(above.any(axis=1) & ~above.all(axis=1))
    corners, zc, side = mesh.vertices[mesh.faces[crossing]], z[crossing], above[crossing]  # (C, 3, 3), (C, 3)
    nxt = [1, 2, 0]  # edges (0, 1), (1, 2), (2, 0): exactly two of them change side
    change = side != side[:, nxt]
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(change, zc / (zc - zc[:, nxt]), 0.0)
    points = corners + (corners[:, nxt] - corners) * t[..., None]
    segments = points[change].reshape(-1, 2, 3)[:, :, :2]
    keep = np.linalg.norm(segments[:, 1] - segments[:, 0], axis=1) > 1e-9
    return merge_collinear(segments[keep], mesh.face_material[crossing][keep])


def merge_collinear(segments: np.ndarray, material: np.ndarray, tolerance: float = 1e-7):
    """Segments (S, 2, 2) of one material that meet end to end on one line, joined into one: a wall's
    triangles cut it into pieces, and a piece's end is no edge of the wall (the caster's specular foot
    must not fall between two pieces). Ends meet within ``tolerance`` (m): the same mesh edge cut twice.
    One pass: each segment joins the collinear pieces already met at its ends, then waits at its own."""
    pieces: dict[int, np.ndarray] = {}
    waiting: dict[tuple, list[int]] = {}  # (material, rounded end) → the pieces ending there

    def key(m: int, point: np.ndarray) -> tuple:
        return (m, *np.round(point / tolerance).astype(np.int64))

    for n, (seg, m) in enumerate(zip(segments, material.tolist())):
        seg = seg.copy()
        joined = True
        while joined:  # at most once per end
            joined = False
            for end in seg:
                for j in waiting.get(key(m, end), []):
                    other, d1 = pieces[j], seg[1] - seg[0]
                    d2 = other[1] - other[0]
                    if abs(d1[0] * d2[1] - d1[1] * d2[0]) > tolerance * np.linalg.norm(d1) * np.linalg.norm(d2):
                        continue  # a corner, not one line
                    for e in pieces.pop(j):
                        waiting[key(m, e)].remove(j)
                    points = np.concatenate([seg, other])
                    t = points @ (d1 / np.linalg.norm(d1))
                    seg, joined = points[[np.argmin(t), np.argmax(t)]], True
                    break
                if joined:
                    break
        pieces[n] = seg
        for e in seg:
            waiting.setdefault(key(m, e), []).append(n)
    order = sorted(pieces)
    return (np.array([pieces[n] for n in order]).reshape(-1, 2, 2),
            np.asarray(material, dtype=np.int64)[order])


def write_mitsuba(path: str | Path, mesh: Mesh, itu: dict[str, ItuMaterial]) -> Path:
    """Write ``mesh`` as a Mitsuba 3 XML scene at ``path`` that Sionna RT and :func:`read_mitsuba` load: one
    binary PLY per material under ``meshes/`` beside it, each a ``<shape type="ply">`` with a ``<ref>`` to a
    bsdf named ``mat-itu_CLASS`` (as Sionna's Blender add-on exports) of that material's ITU class ``itu``.
    Each file is written to a temporary name, then renamed; the XML last."""
    path = Path(path)
    (path.parent / "meshes").mkdir(parents=True, exist_ok=True)
    shapes, bsdfs = [], {}
    for m in np.unique(mesh.face_material):
        part, name = mesh.of_material(int(m)), mesh.material_names[m]
        vertex = np.empty(len(part.vertices), dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4")])
        vertex["x"], vertex["y"], vertex["z"] = part.vertices.T
        face = np.empty(len(part.faces), dtype=[("vertex_indices", "<i4", (3,))])
        face["vertex_indices"] = part.faces
        target = path.parent / "meshes" / f"{name}.ply"
        _replace(target, lambda tmp, v=vertex, f=face: PlyData(
            [PlyElement.describe(v, "vertex"), PlyElement.describe(f, "face")]).write(str(tmp)))
        cls = itu[name].value
        bsdfs[cls] = f'  <bsdf type="twosided" id="mat-itu_{cls}"><bsdf type="principled"/></bsdf>\n'
        shapes.append(f'  <shape type="ply" id="{name}"><string name="filename" value="meshes/{name}.ply"/>'
                      f'<ref id="mat-itu_{cls}" name="bsdf"/></shape>\n')
    xml = f'<scene version="2.1.0">\n{"".join(bsdfs.values())}{"".join(shapes)}</scene>\n'
    _replace(path, lambda tmp: tmp.write_text(xml, encoding="utf-8"))
    return path


def _replace(target: Path, write) -> None:
    tmp = target.with_name(f".{target.name}.tmp")
    write(tmp)
    tmp.replace(target)
