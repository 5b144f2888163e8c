"""Mapping as a recorder writes (issue #14): ``radioslam slam DIR --follow`` feeds each scan
``DIR/scans/NNNN.ply`` to a :class:`~radioslam.slam.session.SlamSession` as soon as it appears and
reports its pose at once; when the walk ends (the recorder writes ``DIR/scans/END``, or no new scan
came for ``idle_s`` seconds, or Ctrl-C) it writes the same outputs as ``radioslam slam DIR``, which
they equal: an offline run is a session fed every scan.

A scan counts once its final name exists: radioslam's writers (and any recorder that writes to a
temporary name and renames it) never show a half-written file; a file that does not parse yet is
read again until the walk's idle time runs out.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from radioslam.errors import RadioslamError
from radioslam.io import read_scan
from radioslam.io.rundir import RunDir
from radioslam.pipeline import write_slam_outputs
from radioslam.sensing.pointcloud import Scan
from radioslam.slam import ScanUpdate, SlamConfig, SlamResult, SlamSession

END_MARKER = "END"  # scans/END: the recorder's walk is over


@dataclass
class ScanFeed:
    """The scans of a run directory in pose order, waiting for each to appear."""

    run: RunDir
    idle_s: float  # the walk ended when no new scan came for this long
    poll_s: float = 0.1
    clock: Callable[[], float] = field(default=time.monotonic)

    def next(self, k: int) -> Scan | None:
        """Scan k once its file is there and parses; None when the walk ended first."""
        path, deadline, failure = self.run.scan_file(k), self.clock() + self.idle_s, None
        while True:
            ended = (self.run.scans / END_MARKER).exists()  # looked at before the scan: one written before END counts
            if path.exists():
                try:
                    return read_scan(path)
                except RadioslamError as exc:  # written in place by a recorder, not yet whole
                    failure = exc
            elif ended:
                return None
            if self.clock() >= deadline:
                if failure is not None:
                    raise failure
                return None
            time.sleep(self.poll_s)


def follow_stage(out: Path, cfg: SlamConfig | None = None, idle_s: float = 60.0,
                 on_update: Callable[[ScanUpdate], None] | None = None) -> SlamResult:
    """SLAM on the scans of ``out`` as they appear; each scan's pose to ``on_update`` at once; when the
    walk ends, the outputs of the slam stage."""
    run, cfg = RunDir(out), cfg or SlamConfig()
    feed, session, scans = ScanFeed(run, idle_s), SlamSession(cfg), []
    tick = time.perf_counter()
    try:
        while (scan := feed.next(len(scans))) is not None:
            scans.append(scan)
            update = session.add(scan)
            if on_update is not None:
                on_update(update)
    except KeyboardInterrupt:  # the user ends the walk: what came so far is mapped
        pass
    if not scans:
        raise RadioslamError(f"no scan (0000.ply) appeared within {idle_s:g} s", file=run.scans, field="(directory)")
    try:
        result = session.finish()
    except RadioslamError as exc:
        raise RadioslamError(exc.reason, file=exc.file or run.scans, field=exc.field) from None
    write_slam_outputs(run, scans, result, cfg, {"slam": time.perf_counter() - tick, "follow_idle_s": idle_s})
    return result
