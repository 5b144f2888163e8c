"""Mapping as a recorder writes (issue #14): ``radioslam slam DIR --follow`` feeds each pose's scan to
a :class:`~radioslam.slam.session.SlamSession` as soon as it appears and reports its pose at once:
``DIR/scans/NNNN.ply``, or a recording ``DIR/captures/NNNN.sigmf-{meta,data}``, sensed then (with
``DIR/calibration.json``) and written as that scan. When the walk ends (the recorder writes ``END`` in
``scans/`` or ``captures/``, or nothing new came for ``idle_s`` seconds, or Ctrl-C) it writes the same
outputs as ``radioslam slam DIR``, which they equal: an offline run is a session fed every scan.

A file counts once its final name exists: radioslam's writers (and any recorder that writes to a
temporary name and renames it) never show a half-written file; a file that does not parse yet is
read again until the walk's idle time runs out.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from contextlib import nullcontext
from dataclasses import dataclass, field
from pathlib import Path

from radioslam.capture import Capture
from radioslam.errors import RadioslamError
from radioslam.io import read_calibration, read_capture, read_scan, write_scan
from radioslam.io.manifest import RunManifest
from radioslam.io.rundir import RunDir
from radioslam.io.sigmf_io import data_path, meta_path
from radioslam.pipeline import write_slam_outputs
from radioslam.sensing import Receiver, SensingConfig
from radioslam.sensing.pointcloud import Scan
from radioslam.slam import ScanUpdate, SlamConfig, SlamResult, SlamSession

END_MARKER = "END"  # scans/END or captures/END: the recorder's walk is over


@dataclass
class ScanFeed:
    """The scans of a run directory in pose order, waiting for each to appear (as a scan, or as a
    recording that ``sense`` turns into one)."""

    run: RunDir
    idle_s: float  # the walk ended when no new scan came for this long
    sense: Callable[[Capture], Scan] | None = None  # recordings: None, only scans are read
    poll_s: float = 0.1
    clock: Callable[[], float] = field(default=time.monotonic)

    def _arrived(self, k: int) -> Scan | None:
        """Pose k's scan if its file (or its recording) is there."""
        path, base = self.run.scan_file(k), self.run.capture_base(k)
        if path.exists():
            return read_scan(path)
        if self.sense is not None and meta_path(base).exists() and data_path(base).exists():
            scan = self.sense(read_capture(base))
            write_scan(path, scan, comment=f"pose {k}")
            return scan
        return None

    def next(self, k: int) -> Scan | None:
        """Scan k once its file is there and parses; None when the walk ended first."""
        deadline, failure = self.clock() + self.idle_s, None
        while True:
            # looked at before the files: one written before END counts
            ended = any((folder / END_MARKER).exists() for folder in (self.run.scans, self.run.captures))
            try:
                scan = self._arrived(k)
            except RadioslamError as exc:  # written in place by a recorder, not yet whole
                scan, failure = None, exc
            if scan is not None:
                return scan
            if ended and failure is None:
                return None
            if self.clock() >= deadline:
                if failure is not None:
                    raise failure
                return None
            time.sleep(self.poll_s)


class RecordingSensor:
    """Recordings to scans with the run's calibration (read when the first recording comes) and the
    receiver settings ``sensing``; one receiver for the walk, as ``radioslam sense`` builds."""

    def __init__(self, run: RunDir, sensing: SensingConfig | None = None):
        self.run, self.sensing, self.receiver = run, sensing, None

    def __call__(self, capture: Capture) -> Scan:
        if self.receiver is None:
            cal = read_calibration(self.run.calibration)
            self.receiver = Receiver(capture.radio, cal.hardware_delay_s, self.sensing, cal.leakage)
        return self.receiver.sense(capture).scan


def follow_stage(out: Path, cfg: SlamConfig | None = None, idle_s: float = 60.0,
                 on_update: Callable[[ScanUpdate], None] | None = None,
                 sensing: SensingConfig | None = None) -> SlamResult:
    """SLAM on the scans of ``out`` (or its recordings, sensed with ``sensing``) as they appear; each
    scan's pose to ``on_update`` at once; when the walk ends, the outputs of the slam stage."""
    run, cfg, manifest = RunDir(out), cfg or SlamConfig(), RunManifest(out)
    feed, session, scans = ScanFeed(run, idle_s, RecordingSensor(run, sensing)), SlamSession(cfg), []
    tick = time.perf_counter()
    # a run of ours: this walk's scans replace its sense stage (and what followed it); a recorder's
    # directory without run.json is adopted when the walk ends (its scans, as found)
    settings = {"follow": True, "sensing": (sensing or SensingConfig()).model_dump(mode="json")}
    with manifest.stage("sense", settings) if manifest.load() is not None else nullcontext():
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
    with manifest.stage("slam", {"slam": cfg.model_dump(mode="json"), "follow": True}):
        write_slam_outputs(run, scans, result, cfg, {"slam": time.perf_counter() - tick, "follow_idle_s": idle_s})
    return result
