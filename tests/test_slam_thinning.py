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


def _corridor_walk(scans: int, spacing_m: float, points: int):
    """A walk of ``scans`` straight steps along a corridor's walls (y = ±2 m), each scan ``points`` wall
    points within ±10 m ahead and behind, with specular normals, as the matchers see them."""
    from radioslam.slam.scan_points import ScanPoints

    x = np.linspace(-10.0, 10.0, points // 2)
    xy = np.concatenate([np.column_stack([x, np.full_like(x, 2.0)]), np.column_stack([x, np.full_like(x, -2.0)])])
    normals = np.concatenate([np.full(len(x), np.pi / 2), np.full(len(x), -np.pi / 2)])
    free = np.column_stack([np.zeros(40), np.linspace(-1.9, 1.9, 40)])
    estimates = {k: np.array([k * spacing_m, 0.0, 0.0]) for k in range(scans)}
    return {k: ScanPoints(xy, normals, free) for k in range(scans)}, estimates


def test_the_whole_map_grid_stays_bounded_however_long_the_walk():
    # issue #15: relocalization's whole-map grid covered every scan ever taken: a 600 m walk at 5 cm cells
    # asked for ≈ 12,000 × 560 cells (≈ 0.8 GB while built); now the square within relocalize_radius_m
    from radioslam.slam.loop_closer import LoopCloser

    cfg = SlamConfig()
    closer = LoopCloser.from_config(cfg)
    scans, estimates = _corridor_walk(300, 2.0, 1024)
    for k, points in scans.items():
        closer.keyframes.insert(k, points)
    keys = list(scans)
    tracemalloc.start()
    grid, normals = closer.whole_map(keys, estimates)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    side = 2 * (cfg.loop_closure.relocalize_radius_m + cfg.loop_closure.relocalize_margin_m) / cfg.grid.resolution_m
    assert grid.values.shape[0] <= side + 2 and peak < 300 * 2**20
    latest = estimates[keys[-1]][:2]
    reach = cfg.loop_closure.relocalize_radius_m + 1e-9
    assert np.all(np.abs(grid.origin + cfg.loop_closure.relocalize_margin_m - latest) <= reach)
    # a map within the square is the whole map, cell for cell
    short = keys[:10]
    clipped = closer.whole_map(short, estimates)[0]
    from radioslam.slam.grid import LikelihoodGrid
    from radioslam.slam.scan_points import fused_free, fused_points

    xy, nrm = fused_points(short, estimates, closer.keyframes.points, np.zeros(3))
    g = cfg.grid
    whole = LikelihoodGrid.from_points(xy, g.resolution_m, g.sigma_m, cfg.loop_closure.relocalize_margin_m, nrm,
                                       np.radians(g.normal_sigma_deg), g.plane_reach_m,
                                       fused_free(short, estimates, closer.keyframes.points), g.free_penalty)
    assert np.array_equal(clipped.fields, whole.fields) and np.array_equal(clipped.origin, whole.origin)
