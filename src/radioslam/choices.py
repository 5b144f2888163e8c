"""Enums the core defines and the command line offers as choices, kept free of numpy and pydantic so that
``radioslam --help`` stays quick (the CLI imports the stages lazily)."""

from __future__ import annotations

from enum import Enum


class ChannelKind(str, Enum):
    """``--channel`` ★ (issue #16): where the echo paths come from, the built-in caster or Sionna RT."""

    BUILTIN = "builtin"
    SIONNA = "sionna"
