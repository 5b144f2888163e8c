"""Where a pose's echo paths come from (issue #16): the built-in 2D ray caster (:mod:`radioslam.sim.paths`,
the default, unchanged) or Sionna RT on the scene extruded to 3D (:mod:`radioslam.sim.sionna_channel`).
Both give :class:`~radioslam.sim.paths.EchoPaths`, which the waveform synthesis and the receiver take
as they are. One factory, :func:`make_channel`, as kiss-icp builds its components from the config."""

from __future__ import annotations

from typing import Protocol

import numpy as np

from radioslam.choices import ChannelKind
from radioslam.config import RadioConfig
from radioslam.errors import RadioslamError
from radioslam.scene.materials import BUILTIN_BY_ITU
from radioslam.scene.model import Scene
from radioslam.sim.errors import SimulationError
from radioslam.sim.paths import EchoPaths, echo_paths


class TraceStore(Protocol):
    """Where a ray tracer's traces are kept between runs (:class:`radioslam.io.trace_cache.TraceCache`)."""

    def load(self, key: str) -> dict[str, np.ndarray] | None: ...

    def store(self, key: str, arrays: dict[str, np.ndarray]) -> None: ...


class ChannelBackend(Protocol):
    def paths(self, pose: np.ndarray, leakage: bool = True) -> EchoPaths:
        """Every echo path of the terminal at ``pose`` (x, y, θ)."""
        ...


class BuiltinChannel:
    """The built-in 2D caster: diffuse rays, image-source (or facet) speculars, leakage."""

    def __init__(self, scene: Scene, radio: RadioConfig):
        check_channel(ChannelKind.BUILTIN, scene)
        self.scene, self.radio = scene, radio

    def paths(self, pose: np.ndarray, leakage: bool = True) -> EchoPaths:
        return echo_paths(self.scene, pose, self.radio, leakage)


def make_channel(kind: ChannelKind, scene: Scene, radio: RadioConfig | None = None,
                 trace_cache: TraceStore | None = None) -> ChannelBackend:
    """The backend of ``kind`` for ``scene`` (its own radio unless ``radio`` is given); Sionna RT is
    imported only here, and its absence is a one-line error saying how to install it. Sionna's traces
    are kept in ``trace_cache`` (a :class:`TraceStore`) when one is given;
    the caster's are not (it traces a pose faster than an archive of its paths is read)."""
    radio = radio or scene.radio
    if ChannelKind(kind) is ChannelKind.SIONNA:
        from radioslam.sim.sionna_channel import SionnaChannel  # optional extra: imported when asked for

        return SionnaChannel(scene, radio, cache=trace_cache)
    return BuiltinChannel(scene, radio)


def check_channel(kind: ChannelKind, scene: Scene, source: str | None = None) -> None:
    """Before anything is written: the backend of ``kind`` can run on ``scene`` (Sionna RT installed, the
    scene extruded, every material with an ITU class), or a one-line error naming what is missing (and
    the scene file, ``source``)."""
    if ChannelKind(kind) is ChannelKind.BUILTIN and scene.spec.mitsuba is not None and scene.radio.elevation_beams > 1:
        raise SimulationError("the built-in caster knows a mitsuba scene only as its horizontal slice: elevation "
                              "beams need --channel sionna", file=source, field="--channel")
    if ChannelKind(kind) is ChannelKind.BUILTIN and scene.spec.mitsuba is not None:
        used = {scene.materials[m].itu for m in np.unique(scene.segment_material)}
        unknown = sorted(c.value for c in used - BUILTIN_BY_ITU.keys())
        if unknown:
            raise SimulationError(f"the built-in caster has no 2D model of ITU class(es) {', '.join(unknown)} in the "
                                  "mitsuba scene: run --channel sionna", file=source, field="--channel")
    if ChannelKind(kind) is ChannelKind.SIONNA:
        from radioslam.sim.sionna_channel import check_scene, import_sionna

        import_sionna()
        try:
            check_scene(scene)
        except RadioslamError as exc:
            raise type(exc)(exc.reason, file=exc.file or source, field=exc.field) from None
