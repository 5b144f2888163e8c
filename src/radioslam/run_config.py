"""A run's config file (``--config FILE``, issue #17): YAML with a ``radio:``, a ``sensing:`` and a ``slam:``
section, each validated by its stage's model (:class:`~radioslam.config.RadioConfig`,
:class:`~radioslam.sensing.config.SensingConfig`, :class:`~radioslam.slam.config.SlamConfig`). ``radio:``
replaces fields of the scene's radio; the other two are whole stage configs (their defaults where a key is
absent). A key beside the three sections, or a bad field, is one error naming the file and the dotted key.

    radio: {snr_db: 5, elevation_beams: 3}
    sensing: {detector: multi}
    slam: {loop_closure: {loop_matches_per_scan: 2}}
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from radioslam.config import RadioConfig
from radioslam.config_file import load_section, read_yaml, validated
from radioslam.errors import RadioslamError
from radioslam.sensing.config import SensingConfig
from radioslam.slam.config import SlamConfig

SECTIONS = ("radio", "sensing", "slam")


class ConfigError(RadioslamError):
    """A config file that cannot be used."""


@dataclass(frozen=True)
class RunConfig:
    """What a config file sets: radio fields to replace, the receiver and the SLAM."""

    radio: dict = field(default_factory=dict)
    sensing: SensingConfig = field(default_factory=SensingConfig)
    slam: SlamConfig = field(default_factory=SlamConfig)


def load_run_config(path: str | Path | None) -> RunConfig:
    """The config file at ``path`` (None: every default)."""
    if path is None:
        return RunConfig()
    path = Path(path)
    doc = read_yaml(path, ConfigError)
    doc = {} if doc is None else doc
    if not isinstance(doc, dict):
        raise ConfigError("a config file is a mapping of sections (radio, sensing, slam)", file=path, field="(top)")
    unknown = sorted(str(k) for k in doc if k not in SECTIONS)
    if unknown:
        raise ConfigError(f"unknown section (known: {', '.join(SECTIONS)})", file=path, field=unknown[0])
    return RunConfig(_radio_fields(doc.get("radio"), path), load_section(path, "sensing", SensingConfig, ConfigError),
                     load_section(path, "slam", SlamConfig, ConfigError))


def _radio_fields(section: object, path: Path) -> dict:
    """The radio fields a ``radio:`` section replaces, each checked as RadioConfig checks it (the combination
    is checked again against the scene's own radio when it is applied)."""
    if section is None:
        return {}
    if not isinstance(section, dict):
        raise ConfigError("must be a mapping of radio fields", file=path, field="radio")
    checked = validated(RadioConfig, section, path, ConfigError, "radio")
    return {key: getattr(checked, key) for key in section}
