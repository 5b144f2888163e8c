"""Scene-file errors, and the one-line form of a pydantic validation error."""

from __future__ import annotations

from pydantic import ValidationError

from radioslam.errors import RadioslamError


class SceneError(RadioslamError):
    """A scene file that cannot be read or does not follow the schema."""


_MESSAGES = {
    "extra_forbidden": "unknown key",
    "missing": "required key is missing",
}


def _key_path(loc: tuple) -> str:
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += ("." if out else "") + str(part)
    return out or "(top level)"


def _reason(error: dict) -> str:
    if error["type"] in _MESSAGES:
        return _MESSAGES[error["type"]]
    msg = str(error["msg"]).removeprefix("Value error, ")
    return f"{msg} (got {error['input']!r})" if error["type"] != "value_error" and \
        not isinstance(error["input"], (dict, list)) else msg


def validation_error(exc: ValidationError, source: str | None, prefix: tuple = ()) -> SceneError:
    """The first pydantic error as a one-line SceneError naming the key path."""
    first = exc.errors()[0]
    loc = prefix + tuple(p for p in first["loc"] if not (isinstance(p, str) and p.startswith("function-")))
    return SceneError(_reason(first), file=source, field=_key_path(loc))
