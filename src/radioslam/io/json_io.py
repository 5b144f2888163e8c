"""Strict JSON (RFC 8259) for every file radioslam reads or writes (issue #15 point 4).

What is written never holds NaN or ±Infinity: a figure that does not exist is ``null``, which
every JSON parser reads. A document being read is refused, as one error naming the file, when it:
- is not UTF-8, or is not JSON;
- holds NaN or Infinity;
- repeats a key in one object (Python would keep the last one silently);
- nests too deep for the parser;
- holds a number too long to convert;
- is bigger than ``MAX_BYTES``.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from radioslam.errors import RadioslamError
from radioslam.text_file import read_text

MAX_BYTES = 64 * 2**20


def finite_or_none(value: Any) -> Any:
    """``value`` with every non-finite float (NaN, ±inf; numpy scalars and arrays too) replaced by None."""
    if isinstance(value, dict):
        return {k: finite_or_none(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [finite_or_none(v) for v in value]
    if isinstance(value, np.ndarray):
        return finite_or_none(value.tolist())
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def dumps(doc: Any, indent: int | None = None) -> str:
    """Strict JSON text of ``doc`` (non-finite numbers as null)."""
    return json.dumps(finite_or_none(doc), indent=indent, allow_nan=False, ensure_ascii=False)


def _refuse_constant(name: str):
    raise ValueError(f"{name} is not JSON (a missing number is null)")


def _unique_keys(pairs: list[tuple[str, Any]]) -> dict:
    doc: dict = {}
    for key, value in pairs:
        if key in doc:
            raise ValueError(f"the key {key!r} appears twice in one object")
        doc[key] = value
    return doc


def loads(text: str, file: str | Path, error: type[RadioslamError] = RadioslamError) -> Any:
    """Parse strict JSON ``text`` read from ``file``; errors as ``error`` naming it."""
    try:
        return json.loads(text, object_pairs_hook=_unique_keys, parse_constant=_refuse_constant)
    except json.JSONDecodeError as exc:
        raise error(f"not valid JSON: {exc.msg} (line {exc.lineno}, column {exc.colno})", file=file,
                    field="(document)") from None
    except RecursionError:
        raise error("nested too deep to read", file=file, field="(document)") from None
    except ValueError as exc:  # a repeated key, NaN, a number of thousands of digits
        raise error(f"not valid JSON: {exc}", file=file, field="(document)") from None


def read_json(path: str | Path, error: type[RadioslamError] = RadioslamError) -> Any:
    """The strict JSON document in the regular file ``path`` (at most ``MAX_BYTES``)."""
    return loads(read_text(path, error, MAX_BYTES), path, error)
