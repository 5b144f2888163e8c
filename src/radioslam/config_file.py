"""The YAML config file (``--config FILE``): one section per stage, each validated by that stage's
own pydantic model (``slam:`` by :class:`~radioslam.slam.config.SlamConfig`, ``sensing:`` by
:class:`~radioslam.sensing.config.SensingConfig`); a bad file or field raises the stage's own error,
naming the file and the dotted field."""

from __future__ import annotations

from pathlib import Path
from typing import TypeVar

import yaml
from pydantic import BaseModel, ValidationError

from radioslam.errors import RadioslamError

Model = TypeVar("Model", bound=BaseModel)


def load_section(path: str | Path, section: str, model: type[Model], error: type[RadioslamError]) -> Model:
    """The ``section`` of the YAML file at ``path`` as ``model`` (its defaults where the section is
    absent); ``error`` is raised for a missing or malformed file or an invalid field."""
    path = Path(path)
    try:
        doc = yaml.safe_load(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise error("no such file", file=path, field="(file)") from None
    except yaml.YAMLError as exc:
        raise error(f"not YAML: {str(exc).splitlines()[0]}", file=path, field="(file)") from None
    if doc is None:
        doc = {}
    if not isinstance(doc, dict):
        raise error("a config file is a mapping of sections", file=path, field="(top)")
    try:
        return model.model_validate(doc.get(section) or {})
    except ValidationError as exc:
        first = exc.errors()[0]
        where = ".".join([section, *(str(p) for p in first["loc"])])
        raise error(first["msg"], file=path, field=where) from None
