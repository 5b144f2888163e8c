"""Online SLAM (issue #14): a session fed one scan at a time, and ``radioslam slam DIR --follow``
mapping scans while a writer thread records them."""

import shutil
import subprocess
import sys
import threading
import time

import numpy as np

from radioslam.io import read_scan


def _record(src, dst, pause_s: float, end: bool) -> threading.Thread:
    """A recorder in a thread: the scans of ``src`` written into ``dst/scans`` one by one (each to a
    temporary name, then renamed), ``pause_s`` apart, then scans/END if ``end``."""

    def write():
        scans = dst / "scans"
        scans.mkdir(parents=True, exist_ok=True)
        for path in sorted((src / "scans").glob("[0-9][0-9][0-9][0-9].ply")):
            time.sleep(pause_s)
            shutil.copyfile(path, scans / f".{path.name}.tmp")
            (scans / f".{path.name}.tmp").rename(scans / path.name)
        if end:
            (scans / "END").write_text("")

    thread = threading.Thread(target=write)
    thread.start()
    return thread


def test_a_session_fed_scan_by_scan_ends_with_the_offline_trajectory(demo_run):
    """A SlamSession asked for its poses and map after every scan gives, once finished, the offline
    run's trajectory exactly; each scan's pose is there at once, and the map grows by its points."""
    from radioslam.slam import RadioSlam, SlamSession

    out, _ = demo_run
    scans = [read_scan(p) for p in sorted((out / "scans").glob("[0-9][0-9][0-9][0-9].ply"))]
    offline = RadioSlam().run(scans)
    session, sizes = SlamSession(), []
    for k, scan in enumerate(scans):
        update = session.add(scan)
        assert update.key == k and np.all(np.isfinite(update.pose))
        assert session.poses.shape == (k + 1, 3) and np.array_equal(session.poses[k], update.pose)
        sizes.append(len(session.map_points()))
    assert np.all(np.diff(sizes) >= 0) and sizes[-1] > 0
    online = session.finish()
    assert np.array_equal(online.poses, offline.poses)
    assert [s.value for s in online.status] == [s.value for s in offline.status]


def test_follow_maps_scans_as_a_writer_thread_records_them(demo_run, tmp_path):
    """follow_stage while a thread writes the scans: every scan's pose reported as it comes, in order,
    the walk ended by scans/END, and the outputs equal those of the offline slam stage on the same
    directory (trajectory.tum byte for byte)."""
    from radioslam.live import follow_stage
    from radioslam.pipeline import slam_stage

    out, _ = demo_run
    count = len(list((out / "scans").glob("[0-9][0-9][0-9][0-9].ply")))
    updates = []
    writer = _record(out, tmp_path, 0.02, end=True)
    follow_stage(tmp_path, idle_s=60.0, on_update=updates.append)
    writer.join()
    assert [u.key for u in updates] == list(range(count))
    live = (tmp_path / "trajectory.tum").read_bytes()
    slam_stage(tmp_path)
    assert (tmp_path / "trajectory.tum").read_bytes() == live


def test_follow_on_the_command_line_ends_after_the_idle_time(demo_run, tmp_path):
    """``radioslam slam DIR --follow --idle 3`` while a thread writes (no END marker): one line per scan
    on stderr, exit 0 after the idle time, the trajectory written; an empty directory ends in exit
    status 2 and one line naming it."""
    out, _ = demo_run
    count = len(list((out / "scans").glob("[0-9][0-9][0-9][0-9].ply")))
    writer = _record(out, tmp_path / "live", 0.05, end=False)
    done = subprocess.run([sys.executable, "-m", "radioslam.cli", "slam", str(tmp_path / "live"), "--follow",
                           "--idle", "3"], capture_output=True, text=True, timeout=600)
    writer.join()
    assert done.returncode == 0, done.stderr
    lines = [line for line in done.stderr.splitlines() if line.startswith("scan ")]
    assert [int(line.split(":")[0].split()[1]) for line in lines] == list(range(count))
    assert len((tmp_path / "live" / "trajectory.tum").read_text().splitlines()) == 1 + count  # a header line
    empty = tmp_path / "empty"
    empty.mkdir()
    failed = subprocess.run([sys.executable, "-m", "radioslam.cli", "slam", str(empty), "--follow", "--idle", "0.3"],
                            capture_output=True, text=True, timeout=120)
    assert failed.returncode == 2
    assert len(failed.stderr.strip().splitlines()) == 1
    assert "scans" in failed.stderr and "Traceback" not in failed.stderr


def test_follow_senses_recordings_as_they_appear(tmp_path):
    """A recorder writing SigMF recordings (data, then meta renamed into place) and the calibration:
    follow_stage senses each as it comes with calibration.json and maps it; the scan it writes equals
    what ``radioslam sense`` makes of the same recording."""
    from radioslam.live import follow_stage

    recorded = tmp_path / "recorded"
    done = subprocess.run([sys.executable, "-m", "radioslam.cli", "simulate", "single-plate:3", "--out", str(recorded),
                           "--save-iq", "--seed", "2"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    live = tmp_path / "live"

    def record():
        (live / "captures").mkdir(parents=True)
        shutil.copyfile(recorded / "calibration.json", live / "calibration.json")
        time.sleep(0.2)
        for suffix in (".sigmf-data", ".sigmf-meta"):
            shutil.copyfile(recorded / "captures" / f"0000{suffix}", live / "captures" / f".tmp{suffix}")
            (live / "captures" / f".tmp{suffix}").rename(live / "captures" / f"0000{suffix}")
        (live / "captures" / "END").write_text("")

    writer = threading.Thread(target=record)
    writer.start()
    updates = []
    follow_stage(live, idle_s=60.0, on_update=updates.append)
    writer.join()
    assert [u.key for u in updates] == [0]
    sensed = subprocess.run([sys.executable, "-m", "radioslam.cli", "sense", str(recorded), "--plot-pose", "-1"],
                            capture_output=True, text=True, timeout=300)
    assert sensed.returncode == 0, sensed.stderr
    ours, theirs = read_scan(live / "scans" / "0000.ply"), read_scan(recorded / "scans" / "0000.ply")
    assert len(ours) > 0 and np.array_equal(ours.range_m, theirs.range_m) and np.array_equal(ours.beam, theirs.beam)
    assert (live / "trajectory.tum").exists()


def test_the_live_map_composed_from_submaps_agrees_with_the_map_of_the_same_poses(demo_run):
    """SlamSession.occupancy(): each submap's hits and clearing rays in its first scan's frame, counted once
    when full, placed at that scan's latest pose. On the demo's walk it agrees with the grid built from
    every scan at the back end's latest poses (occupancy_grid): ≥ 95 % of that grid's occupied cells are
    occupied in the live map within one cell (a submap's cells are resampled to the nearest world cell,
    and its scans sit where they were relative to its first when they came), ≥ 95 % of its free cells
    free; a full submap is counted once."""
    from scipy.ndimage import maximum_filter

    from radioslam.slam import SlamSession
    from radioslam.slam.occupancy import occupancy_grid

    out, _ = demo_run
    scans = [read_scan(p) for p in sorted((out / "scans").glob("[0-9][0-9][0-9][0-9].ply"))]
    session = SlamSession()
    assert session.occupancy() is None
    for scan in scans:
        session.add(scan)
    live = session.occupancy()
    first = session.map.parts[0].counts
    assert first is not None and session.occupancy() is not None and session.map.parts[0].counts is first
    exact = occupancy_grid(session.poses, [s.xy for s in scans], session.cfg.map)
    centres = exact.origin + (np.argwhere(np.ones(exact.log_odds.shape, bool)) + 0.5) * exact.resolution
    cells = np.floor((centres - live.origin) / live.resolution).astype(int)
    inside = np.all((cells >= 0) & (cells < live.log_odds.shape), axis=1)

    def at_exact_cells(values: np.ndarray) -> np.ndarray:
        sampled = np.zeros(len(centres))
        sampled[inside] = values[cells[inside, 0], cells[inside, 1]]
        return sampled

    theirs = exact.log_odds.ravel()
    assert np.mean(at_exact_cells(maximum_filter(live.log_odds, 3))[theirs > 0] > 0) >= 0.95
    assert np.mean(at_exact_cells(live.log_odds)[theirs < 0] < 0) >= 0.95
