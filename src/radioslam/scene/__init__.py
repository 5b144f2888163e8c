"""Scenes: the ★ scene-file schema, materials, geometry, trajectories, ray casting."""

from pathlib import Path

from radioslam.scene.builtin import BUILTIN_SCENES, builtin_scene
from radioslam.scene.errors import SceneError
from radioslam.scene.loader import load_scene_file, scene_from_mapping, scene_to_yaml
from radioslam.scene.materials import BUILTIN_MATERIALS, Material
from radioslam.scene.model import Scene
from radioslam.scene.raycast import RayHits, cast_rays


def load_scene(name_or_path: str | Path) -> Scene:
    """A scene file, or a built-in scene when no such file exists."""
    path = Path(name_or_path)
    if path.exists() or path.suffix in (".yaml", ".yml"):
        return load_scene_file(path)
    return builtin_scene(str(name_or_path))


__all__ = ["BUILTIN_MATERIALS", "BUILTIN_SCENES", "Material", "RayHits", "Scene", "SceneError",
           "builtin_scene", "cast_rays", "load_scene", "load_scene_file", "scene_from_mapping",
           "scene_to_yaml"]
