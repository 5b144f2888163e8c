"""The SLAM's structure (issue #47, point 5): one scan matcher (branch and bound → distinct candidates → refinement →
response covariance → degeneracy) that the front end, the loop closer and relocalization each hold with their own
options, and one map of keyframes and submaps that they all read, updated by insertion."""

import numpy as np
import pytest
from test_slam import room_points

from radioslam.slam.config import SlamConfig
from radioslam.slam.front_end import FrontEnd
from radioslam.slam.grid import LikelihoodGrid
from radioslam.slam.loop_closer import LoopCloser
from radioslam.slam.scan_matcher import front_end_matcher, loop_matcher, relocalization_matcher
from radioslam.slam.se2 import inverse, transform_points, wrap_angle


def test_the_matcher_finds_a_turned_scan_off_the_lattice_and_tells_a_room_from_a_corridor(rng):
    """A scan of a room 1 m and 25° from the search's centre: every heading its normals suggest, branch and bound
    over ±1.5 m, the distinct candidates refined, give the true pose within the field's quantization (half its
    5 cm cell); the response surface's covariance is a covariance as small as the cell; nothing is weak in a room.
    The same scan cut to two parallel walls (a corridor) leaves the direction along them weak."""
    pts, nrm = room_points(rng, 800)
    grid = LikelihoodGrid.from_points(pts, 0.05, 0.05, 2.0, nrm, np.radians(1.0), 0.5)
    matcher = front_end_matcher(SlamConfig())
    truth = np.array([0.7, -0.6, np.radians(25.0)])
    keep = slice(None, None, 5)
    scan = transform_points(inverse(truth), pts[keep]) + rng.normal(0, 0.005, (len(pts[keep]), 2))
    normals = wrap_angle(nrm[keep] - truth[2])
    headings = matcher.headings(normals, nrm)
    found = matcher.search(grid, scan, normals, np.zeros(2), headings, 1.5, 0.0, matcher.keep_ratio)
    places, _ = matcher.distinct(found.candidates, found.scores)
    assert len(places) <= matcher.options.refined
    refined = matcher.refine(grid, scan, normals, places)
    best = refined[np.argmax(matcher.scores(grid, scan, normals, refined))]
    # within the field's quantization (a map point stands for its cell's centre: half a cell) and below the 0.5°
    # angle lattice, and fitting the scan at least as well as the lattice's best
    assert np.abs(best[:2] - truth[:2]).max() < 0.03 and abs(wrap_angle(best[2] - truth[2])) < np.radians(0.3)
    assert matcher.scores(grid, scan, normals, best[None])[0] >= found.score - 1e-6
    covariance = matcher.response(grid, scan, normals, best).covariance + matcher.floor
    assert np.allclose(covariance, covariance.T) and np.all(np.linalg.eigvalsh(covariance) > 0)
    assert np.sqrt(covariance[0, 0]) < 0.05 and np.sqrt(covariance[1, 1]) < 0.05
    assert matcher.weak(grid, best, scan, normals, covariance) is None
    long_walls = np.abs(np.abs(nrm[keep]) - np.pi / 2) < 1e-9  # the walls at y = ±2 (normals ±90°) alone
    weak = matcher.weak(grid, best, scan[long_walls], normals[long_walls], covariance)
    assert weak is not None and abs(weak[0]) == pytest.approx(1.0, abs=1e-6)  # along x, the corridor's axis


def test_each_component_holds_its_own_matcher_from_its_own_settings():
    """The front end's response surface spans its step window; a loop's twice that (a loop's drift is wider);
    relocalization searches the whole map with more branch-and-bound levels. The loop closer reads no front-end
    setting of its own: what it shares with the front end comes through its matcher."""
    cfg = SlamConfig()
    front, loop, whole = front_end_matcher(cfg), loop_matcher(cfg), relocalization_matcher(cfg)
    f = cfg.front_end
    assert front.options.response_m == f.window_m and loop.options.response_m == 2 * f.window_m
    assert loop.options.response_rad == pytest.approx(2 * front.options.response_rad)
    assert front.options.levels == loop.options.levels == cfg.grid.branch_levels
    assert whole.options.levels == cfg.loop_closure.relocalize_levels
    assert np.allclose(front.floor, loop.floor) and front.keep_ratio == loop.keep_ratio < 1.0
    closer = LoopCloser.from_config(cfg)
    assert closer.matcher.options == loop.options and closer.relocalizer.options == whole.options
    assert not hasattr(closer, "front_cfg")
    assert FrontEnd.from_config(cfg).matcher.options == front.options


def test_the_map_of_keyframes_is_one_store_updated_by_insertion(rng):
    """A session's front end, loop closer and ending read one map of keyframes: every scan not skipped, in the order
    it came, grouped into submaps of ``submap_scans``; a skipped scan is no keyframe (and no submap's)."""
    from test_slam import synthetic_scans

    from radioslam.sensing.pointcloud import Scan
    from radioslam.slam.keyframe_map import KeyframeMap
    from radioslam.slam.scan_points import ScanPoints
    from radioslam.slam.session import SlamSession

    keyframes = KeyframeMap(3)
    for k in (0, 1, 2, 4, 5, 7, 8):
        keyframes.insert(k, ScanPoints(np.zeros((1, 2)), np.zeros(1), np.zeros((0, 2))))
    assert keyframes.keys == [0, 1, 2, 4, 5, 7, 8] == list(keyframes.points)
    assert [s.keys for s in keyframes.submaps] == [[0, 1, 2], [4, 5, 7], [8]]
    assert keyframes.before(5) == [0, 1, 2, 4, 7, 8] and keyframes.before(5, before=5) == [0, 1, 2, 4]

    pts, nrm = room_points(rng, 600)
    poses = np.array([[-1.0 + 0.2 * k, 0.5, 0.0] for k in range(6)])
    scans = synthetic_scans(poses, pts, nrm, rng)
    scans[3] = Scan.empty()
    session = SlamSession(SlamConfig())
    for scan in scans:
        session.add(scan)
    assert session.front_end.keyframes is session.loop_closer.keyframes is session.keyframes
    assert session.keyframes.keys == [0, 1, 2, 4, 5]
    assert sum(len(s.keys) for s in session.keyframes.submaps) == 5
