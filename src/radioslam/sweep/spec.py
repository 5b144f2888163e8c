"""The sweep file (issue #14 ★): which runs a sweep makes.

.. code-block:: yaml

    scenes: [paper-cnv, rooms/l-room.yaml]   # built-in names or scene files
    seeds: [1, 2, 3]
    snr_db: [0, 10, 20]        # optional; the scene's own when absent
    radio: {frames: 2}         # optional overrides of every run's radio, sensing and SLAM settings
    sensing: {detector: matched-filter}
    slam: {loop_closure: {loop_matches_per_scan: 2}}
    variants:                  # optional: more overrides, one more axis of the sweep
      narrow-window: {slam: {front_end: {window_m: 0.5}}}
    robustness: {runs: 40, seed: 0}   # optional: the robustness suite's generated cases, each with
                                      # its own seed and SNR (not crossed with seeds and snr_db)

Every combination of scene × seed × SNR × variant is one :class:`RunSpec`; its ``run_id`` names its
directory and is the same for the same settings, so a sweep run again skips what it finished.
"""

from __future__ import annotations

import hashlib
import json
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from radioslam.config_file import read_yaml, validated
from radioslam.errors import RadioslamError


class SweepError(RadioslamError):
    """A sweep file that cannot be run."""


class Overrides(BaseModel):
    model_config = ConfigDict(extra="forbid")

    radio: dict[str, Any] = Field(default_factory=dict)
    sensing: dict[str, Any] = Field(default_factory=dict)
    slam: dict[str, Any] = Field(default_factory=dict)


class RobustnessBlock(BaseModel):
    model_config = ConfigDict(extra="forbid")

    runs: int = Field(40, ge=1, le=10_000)
    seed: int = Field(0, ge=0)


class SweepSpec(Overrides):
    scenes: list[str] = Field(default_factory=list)
    seeds: list[int] = Field(default_factory=lambda: [0])
    snr_db: list[float] | None = None
    variants: dict[str, Overrides] = Field(default_factory=dict)
    robustness: RobustnessBlock | None = None

    def runs(self) -> list[RunSpec]:
        """Every run of the sweep, in a fixed order."""
        variants = self.variants or {"": Overrides()}
        runs = [RunSpec(scene, seed, snr, name, _merged(self, variant))
                for name, variant in variants.items() for scene in self.scenes for seed in self.seeds
                for snr in (self.snr_db or [None])]
        if self.robustness is not None:
            from radioslam.scene.procedural import robustness_suite

            for case in robustness_suite(self.robustness.runs, self.robustness.seed):
                for name, variant in variants.items():
                    runs.append(RunSpec(case.name, case.seed, case.snr_db, name, _merged(self, variant),
                                        generated={"runs": self.robustness.runs, "seed": self.robustness.seed},
                                        labels={"motion": case.motion.value, "room": case.room.value}))
        return runs


def _merged(base: Overrides, variant: Overrides) -> dict[str, dict]:
    return {section: _deep_merge(getattr(base, section), getattr(variant, section))
            for section in ("radio", "sensing", "slam")}


def _deep_merge(a: dict, b: dict) -> dict:
    out = dict(a)
    for key, value in b.items():
        out[key] = _deep_merge(out[key], value) if isinstance(value, dict) and isinstance(out.get(key), dict) else value
    return out


@dataclass(frozen=True)
class RunSpec:
    """One run of a sweep: a scene (built-in, file, or a generated robustness case), its seed, SNR (None:
    the scene's own), the variant's name and every override."""

    scene: str
    seed: int
    snr_db: float | None
    variant: str
    overrides: dict[str, dict]
    generated: dict | None = None  # the robustness suite the case comes from
    labels: dict[str, str] = field(default_factory=dict)  # motion and room of a generated case

    @property
    def run_id(self) -> str:
        """A directory name: readable, and unique to every setting of the run."""
        key = json.dumps([self.scene, self.seed, self.snr_db, self.variant, self.overrides, self.generated],
                         sort_keys=True)
        slug = re.sub(r"[^A-Za-z0-9._-]+", "-", Path(self.scene).stem if self.scene.endswith(".yaml") else self.scene)
        snr = "own" if self.snr_db is None else f"{self.snr_db:g}"
        return f"{slug[:40]}-s{self.seed}-snr{snr}-{hashlib.sha1(key.encode()).hexdigest()[:10]}"


def load_sweep(path: str | Path) -> SweepSpec:
    """The sweep file at ``path``, validated; a bad file or field raises :class:`SweepError` naming it."""
    path = Path(path)
    doc = read_yaml(path, SweepError)
    if not isinstance(doc, dict):
        raise SweepError("a sweep file is a mapping (scenes:, seeds:, snr_db: …)", file=path, field="(top)")
    spec = validated(SweepSpec, doc, path, SweepError)
    if not spec.scenes and spec.robustness is None:
        raise SweepError("names no run: give scenes: (and seeds:) or robustness:", file=path, field="scenes")
    _check_overrides(spec, path)
    # a scene file is looked for beside the sweep file first, then where the sweep is run
    spec.scenes = [str(path.parent / s) if s.endswith((".yaml", ".yml")) and (path.parent / s).is_file() else s
                   for s in spec.scenes]
    return spec



def _check_overrides(spec: SweepSpec, path: Path) -> None:
    """Every run's radio, sensing and SLAM overrides validated by their stage's own model: a bad one ends
    the sweep before it starts, not as a column of failed runs."""
    from radioslam.config import RadioConfig
    from radioslam.sensing import SensingConfig
    from radioslam.slam import SlamConfig

    models = {"radio": lambda d: RadioConfig(**{**RadioConfig().model_dump(), **d}),
              "sensing": SensingConfig.model_validate, "slam": SlamConfig.model_validate}
    for name, variant in (spec.variants or {"": Overrides()}).items():
        for section, overrides in _merged(spec, variant).items():
            try:
                models[section](overrides)
            except (ValidationError, TypeError) as exc:
                where = ["variants", name] if name and getattr(variant, section) else []
                first = exc.errors()[0] if isinstance(exc, ValidationError) else {"msg": str(exc), "loc": ()}
                raise SweepError(first["msg"], file=path,
                                 field=".".join([*where, section, *(str(p) for p in first["loc"])])) from None
