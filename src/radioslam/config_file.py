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
from radioslam.text_file import read_text

Model = TypeVar("Model", bound=BaseModel)
MAX_BYTES = 16 * 2**20  # a scene, config or sweep file is text of a few kB


class _StrictLoader(yaml.SafeLoader):
    """PyYAML's safe loader refusing a key repeated in one mapping (it would keep the last one silently)."""

    def construct_mapping(self, node, deep=False):
        seen = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=True)
            if key in seen:
                raise yaml.constructor.ConstructorError(None, None, f"the key {key!r} appears twice in one mapping",
                                                        key_node.start_mark)
            seen.add(key)
        return super().construct_mapping(node, deep)


def read_yaml(path: str | Path, error: type[RadioslamError]) -> object:
    """The YAML document in the regular file ``path`` (UTF-8, at most ``MAX_BYTES``; a FIFO or a device would
    block or never end): safe types only, no repeated key, no nesting deeper than the parser can take."""
    path = Path(path)
    text = read_text(path, error, MAX_BYTES)
    try:
        return yaml.load(text, Loader=_StrictLoader)  # noqa: S506 - a SafeLoader subclass
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}" if mark is not None else "(document)"
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise error(f"not valid YAML: {problem}", file=path, field=where) from None
    except RecursionError:
        raise error("not valid YAML: nested too deep to read", file=path, field="(document)") from None
    except ValueError as exc:  # a number of thousands of digits
        raise error(f"not valid YAML: {' '.join(str(exc).split())}", file=path, field="(document)") from None


def load_section(path: str | Path, section: str, model: type[Model], error: type[RadioslamError]) -> Model:
    """The ``section`` of the YAML file at ``path`` as ``model`` (its defaults where the section is
    absent); ``error`` is raised for a missing or malformed file or an invalid field."""
    path = Path(path)
    doc = read_yaml(path, error)
    if doc is None:
        doc = {}
    if not isinstance(doc, dict):
        raise error("a config file is a mapping of sections", file=path, field="(top)")
    return validated(model, doc.get(section) or {}, path, error, section)


def validated(model: type[Model], value: object, path: Path, error: type[RadioslamError], *where: str) -> Model:
    """``value`` as ``model``, or ``error`` naming ``path`` and the first bad field, dotted after ``where``."""
    try:
        return model.model_validate(value)
    except ValidationError as exc:
        first = exc.errors()[0]
        raise error(first["msg"], file=path, field=".".join([*where, *(str(p) for p in first["loc"])])) from None
