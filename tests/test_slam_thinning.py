"""Scans of any size in bounded memory (issue #15 point 3): thinned deterministically before the SLAM."""

import tracemalloc

import numpy as np

from radioslam.sensing.pointcloud import Scan
from radioslam.slam import RadioSlam, SlamConfig
from radioslam.slam.thinning import thin_scan


def _room_scan(rng, points, pose=np.zeros(3), far=0):
    """``points`` echoes on the walls of a 10 × 8 m room seen from ``pose``, and ``far`` points 10 km away."""
    t = rng.uniform(0, 36, points)
    x = np.where(t < 10, t - 5, np.where(t < 18, 5, np.where(t < 28, 23 - t, -5)))
    y = np.where(t < 10, -4, np.where(t < 18, t - 14, np.where(t < 28, 4, 32 - t)))
    xy = np.column_stack([x, y]) - pose[:2]
    c, s = np.cos(pose[2]), np.sin(pose[2])
    local = xy @ np.array([[c, -s], [s, c]])
    local = np.vstack([local, np.full((far, 2), 1e4)])
    power = np.concatenate([rng.uniform(-30, 0, points), np.zeros(far)])
    n = len(local)
    return Scan(np.hypot(*local.T), np.arctan2(local[:, 1], local[:, 0]), power, np.zeros(n, np.int64),
                np.zeros(n, np.int64))


def test_thinning_drops_far_points_then_keeps_each_cells_strongest_then_the_strongest():
    rng = np.random.default_rng(3)
    scan = _room_scan(rng, 50_000, far=7)
    thinned, note = thin_scan(scan, max_points=1000, max_range_m=100.0, cell_m=0.05)
    assert len(thinned) == 1000 and "50,007 points thinned to 1,000 (7 beyond 100 m)" in note
    assert thinned.range_m.max() < 100
    # each cell's strongest point first, then the strongest of those
    near = scan.range_m < 100
    cells = np.floor(scan.xy[near] / 0.05).astype(int)
    cell = np.unique(cells, axis=0, return_inverse=True)[1].reshape(-1)  # numpy 2.0.0 gives (N, 1)
    winners = np.full(cell.max() + 1, -np.inf)
    np.maximum.at(winners, cell, scan.power_db[near])
    np.testing.assert_array_equal(np.sort(thinned.power_db), np.sort(winners)[-1000:])
    again, _ = thin_scan(scan, max_points=1000, max_range_m=100.0, cell_m=0.05)
    np.testing.assert_array_equal(again.range_m, thinned.range_m)  # deterministic
    # one point per cell once cells alone bring it under the cap
    few, _ = thin_scan(scan, max_points=40_000, max_range_m=100.0, cell_m=0.05)
    cells = np.floor(few.xy / 0.05).astype(int)
    assert len(np.unique(cells, axis=0)) == len(few)
    small = _room_scan(rng, 200)
    assert thin_scan(small, 4096, 100.0, 0.05) == (small, "")  # a radio scan passes untouched


def test_slam_maps_a_scan_of_a_million_points_in_bounded_memory():
    rng = np.random.default_rng(4)
    poses = np.array([[0.0, 0.0, 0.0], [0.4, 0.0, 0.0], [0.8, 0.1, 0.05]])
    scans = [_room_scan(rng, 300, poses[0]), _room_scan(rng, 1_000_000, poses[1], far=1),
             _room_scan(rng, 300, poses[2])]
    tracemalloc.start()
    try:
        result = RadioSlam(SlamConfig()).run(scans)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 400 * 2**20, f"{peak / 2**20:.0f} MiB"
    assert any(w.startswith("scan 1: 1,000,001 points thinned to ") and "(1 beyond 100 m)" in w
               for w in result.warnings)
    assert np.all(np.isfinite(result.poses))
