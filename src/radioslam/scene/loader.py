"""Read and write scene files (YAML ★ schema of DESIGN.md §4) with one-line errors."""

from __future__ import annotations

from pathlib import Path

import yaml
from pydantic import ValidationError

from radioslam.scene.errors import SceneError, validation_error
from radioslam.scene.model import Scene, build_scene
from radioslam.scene.schema import SceneSpec


def scene_from_mapping(data: object, source: str | None = None) -> Scene:
    """Validate a parsed YAML document and build the scene."""
    if not isinstance(data, dict):
        raise SceneError(f"the document must be a mapping, got {type(data).__name__}",
                         file=source, field="(top level)")
    try:
        spec = SceneSpec.model_validate(data)
    except ValidationError as exc:
        raise validation_error(exc, source) from None
    return build_scene(spec, source)


def load_scene_file(path: str | Path) -> Scene:
    """Load a scene YAML file."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise SceneError("no such file", file=path, field="(file)") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise SceneError(f"cannot read: {exc}", file=path, field="(file)") from None
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}" if mark is not None else "(document)"
        problem = getattr(exc, "problem", None) or str(exc)
        raise SceneError(f"not valid YAML: {problem}", file=path, field=where) from None
    return scene_from_mapping(data, str(path))


def scene_to_yaml(scene: Scene) -> str:
    """The scene as run, defaults filled in (the ``scene.yaml`` of a run directory)."""
    data = scene.spec.model_dump(mode="json", exclude_none=True)
    return yaml.safe_dump(data, sort_keys=False, default_flow_style=False)
