"""Read and write scene files (YAML ★ schema of DESIGN.md §4) with one-line errors."""

from __future__ import annotations

from pathlib import Path

import yaml
from pydantic import ValidationError

from radioslam.config_file import read_yaml
from radioslam.scene.errors import SceneError, validation_error
from radioslam.scene.model import Scene, build_scene
from radioslam.scene.schema import SceneSpec


def scene_from_mapping(data: object, source: str | None = None) -> Scene:
    """Validate a parsed YAML document and build the scene."""
    if not isinstance(data, dict):
        raise SceneError(f"the document must be a mapping, got {type(data).__name__}",
                         file=source, field="(top level)")
    if "walls" not in data and "mitsuba" not in data:  # walls, unless a Mitsuba scene stands in for them
        raise SceneError("required key is missing (or mitsuba: a Mitsuba XML scene)", file=source, field="walls")
    try:
        spec = SceneSpec.model_validate(data)
    except ValidationError as exc:
        raise validation_error(exc, source) from None
    return build_scene(spec, source)


def load_scene_file(path: str | Path) -> Scene:
    """Load a scene YAML file."""
    return scene_from_mapping(read_yaml(path, SceneError), str(path))


def scene_to_yaml(scene: Scene) -> str:
    """The scene as run, defaults filled in (the ``scene.yaml`` of a run directory)."""
    data = scene.spec.model_dump(mode="json", exclude_none=True)
    return yaml.safe_dump(data, sort_keys=False, default_flow_style=False)
