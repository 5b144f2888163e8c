"""docs/settings.md lists every SLAM setting with its default and unit (issue #47: the settings in one table)."""

from __future__ import annotations

import re
from enum import Enum
from pathlib import Path

from pydantic import BaseModel

from radioslam.slam import SlamConfig

TABLE = Path(__file__).resolve().parents[1] / "docs" / "settings.md"
UNITS = {"_m": "m", "_deg": "°", "_chi2": "χ²"}


def leaves(model: BaseModel, prefix: str = "") -> list[tuple[str, object]]:
    """(dotted name, default) of every leaf setting, in the config's order."""
    out = []
    for name in type(model).model_fields:
        value = getattr(model, name)
        out += leaves(value, f"{prefix}{name}.") if isinstance(value, BaseModel) else [(prefix + name, value)]
    return out


def shown(value: object) -> str:
    if isinstance(value, Enum):
        return str(value.value)
    if isinstance(value, bool):
        return str(value).lower()
    return f"{value:g}" if isinstance(value, float) else str(value)


def table_rows() -> list[list[str]]:
    rows = [[cell.strip() for cell in line.strip().strip("|").split("|")]
            for line in TABLE.read_text(encoding="utf-8").splitlines() if line.startswith("| `")]
    return rows


def test_the_settings_table_lists_every_setting_with_its_default_and_unit():
    rows = table_rows()
    names = [re.fullmatch(r"`(.+)`", row[0]).group(1) for row in rows]
    settings = leaves(SlamConfig())
    assert names == [name for name, _ in settings]
    for row, (name, value) in zip(rows, settings):
        assert row[1] == shown(value), name
        unit = next((u for suffix, u in UNITS.items() if name.endswith(suffix)), "")
        assert row[2] == unit, name
        assert row[4] in {"physics", "probability", "cost", "switch", "rule"}, name
        assert row[5], name


def test_the_count_stated_is_the_table_s():
    stated = re.search(r"Today: \*\*(\d+) settings\*\*", TABLE.read_text(encoding="utf-8"))
    assert stated is not None and int(stated.group(1)) == len(leaves(SlamConfig())) == len(table_rows())
