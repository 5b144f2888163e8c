"""SLAM core: SE(2) algebra, the likelihood pyramid, branch and bound = exhaustive search,
the correlative matcher on synthetic geometry, specular normals, skipped and degenerate scans."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from radioslam.sensing.pointcloud import Scan
from radioslam.slam import RadioSlam, ScanStatus, SlamConfig
from radioslam.slam.branch_bound import BranchAndBound
from radioslam.slam.correlative import candidate_likelihoods, correlative_match
from radioslam.slam.grid import LikelihoodGrid
from radioslam.slam.normals import oblique_walls, specular_arcs, specular_normals
from radioslam.slam.refine import refine_pose
from radioslam.slam.se2 import between, compose, inverse, transform_points

poses3 = st.tuples(st.floats(-10, 10), st.floats(-10, 10), st.floats(-3.1, 3.1)).map(np.array)


@given(poses3, poses3)
@settings(max_examples=50, deadline=None)
def test_se2_compose_between_inverse(a, b):
    assert np.allclose(compose(a, between(a, b)), b, atol=1e-9)
    assert np.allclose(compose(a, inverse(a)), 0, atol=1e-9)
    pts = np.array([[1.0, 2.0], [-3.0, 0.5]])
    assert np.allclose(transform_points(compose(a, b), pts), transform_points(a, transform_points(b, pts)))


def test_pyramid_level_is_the_max_over_its_window(rng):
    """Level 0 holds both fields; each coarser level h the max of both over [i, i + 2^h) × [j, j + 2^h)."""
    point, plane = rng.random((37, 29)) - 0.2, rng.random((37, 29)) - 0.2  # some free (negative) cells
    grid = LikelihoodGrid(point, np.zeros(2), 0.1, np.full((37, 29), np.nan), np.inf, plane)
    levels = grid.pyramid(4)
    assert len(levels) == 5 and np.array_equal(levels[0], np.stack([point, plane]))
    either = np.maximum(point, plane)
    for h, level in enumerate(levels[1:], start=1):
        w = 2**h
        brute = np.array([[either[i:i + w, j:j + w].max() for j in range(29)] for i in range(37)])
        assert level.shape == (1, 37, 29) and np.array_equal(level[0], brute)


def test_plane_field_ignores_the_offset_along_a_wall_within_reach():
    """Point-to-plane (Chen & Medioni 1992): a wall stretch y = 0 (normal +y) scores a point
    by its offset along y only, up to ``plane_reach`` from the nearest wall point."""
    wall = np.column_stack([np.arange(0.0, 1.0, 0.05) + 0.025, np.full(20, 0.025)])
    grid = LikelihoodGrid.from_points(wall, 0.05, 0.05, 1.0, np.full(20, np.pi / 2), np.radians(1.0), 0.5)
    probe = np.array([[1.3, 0.025], [1.3, 0.125], [1.7, 0.025], [0.5, 0.125]])  # beyond the end, above it
    c = grid.cells(probe)
    plane = grid.plane[c[:, 0], c[:, 1]]
    point = grid.values[c[:, 0], c[:, 1]]
    assert plane[0] == pytest.approx(1.0)  # 0.3 m past the end, on the line: within reach
    assert plane[1] == pytest.approx(np.exp(-0.5 * (0.1 / 0.05) ** 2))  # 0.1 m off the line
    assert plane[2] == pytest.approx(point[2]) and point[2] < 1e-6  # 0.7 m past the end: the plain distance
    assert plane[3] == pytest.approx(plane[1]) and plane[3] >= point[3] - 1e-12  # above the middle: the offset


def room_points(rng, n=400):
    """Points on a 6 m × 4 m room with an inner corner, and their outward normals (world)."""
    walls = [((-3, -2), (3, -2), np.pi / 2), ((3, -2), (3, 2), np.pi), ((3, 2), (-3, 2), -np.pi / 2),
             ((-3, 2), (-3, -2), 0.0), ((0, -2), (0, -0.5), np.pi)]
    pts, nrm = [], []
    for a, b, normal in walls:
        t = rng.random(n // len(walls))[:, None]
        pts.append(np.array(a) + t * (np.array(b) - np.array(a)))
        nrm.append(np.full(len(t), normal))
    return np.concatenate(pts), np.concatenate(nrm)


def test_correlative_match_recovers_a_known_pose_and_refinement_sharpens_it(rng):
    pts, nrm = room_points(rng)
    grid = LikelihoodGrid.from_points(pts, 0.05, 0.05, 1.0, nrm, np.radians(1.0))
    truth = np.array([0.4, -0.3, np.radians(3.0)])
    scan = transform_points(inverse(truth), pts[::7]) + rng.normal(0, 0.01, (len(pts[::7]), 2))
    scan_normals = nrm[::7] - truth[2]
    match = correlative_match(grid, scan, scan_normals, np.zeros(3) + [0.3, -0.2, 0.0], 0.3, np.radians(6),
                              np.radians(0.5))
    assert np.abs(match.pose[:2] - truth[:2]).max() <= 0.05 + 1e-9
    refined = refine_pose(grid, scan, scan_normals, match.pose, 0.05, np.radians(0.5))
    assert np.abs(refined[:2] - truth[:2]).max() < 0.02
    assert abs(refined[2] - truth[2]) < np.radians(0.2)
    assert 0.5 < match.score <= 1.0
    # Olson's covariance is a covariance: symmetric, positive definite, of sensible size
    assert np.allclose(match.covariance, match.covariance.T)
    assert np.all(np.linalg.eigvalsh(match.covariance) > 0)
    assert np.sqrt(match.covariance[0, 0]) < 0.1


def test_branch_and_bound_finds_the_exhaustive_optimum_with_fewer_lookups(rng):
    pts, nrm = room_points(rng)
    grid = LikelihoodGrid.from_points(pts, 0.05, 0.05, 2.0, nrm, np.radians(1.0))
    truth = np.array([0.9, 0.6, np.radians(-7.0)])
    scan = transform_points(inverse(truth), pts[::9])
    scan_normals = nrm[::9] - truth[2]
    step = np.radians(1.0)
    found = BranchAndBound(grid, 4).match(scan, scan_normals, np.zeros(3), 1.2, np.radians(10), step, 0.0)
    angles = step * np.arange(-10, 11)
    offsets = np.arange(-24, 25)
    exhaustive = candidate_likelihoods(grid, scan, scan_normals, np.zeros(3), angles, offsets).mean(axis=-1)
    assert found.score == pytest.approx(exhaustive.max(), abs=1e-12)
    assert found.evaluated < found.exhaustive / 5
    assert np.abs(found.pose[:2] - truth[:2]).max() <= 0.05 + 1e-9


def test_seeds_only_speed_branch_and_bound_up(rng):
    """Seeds (a motion model's predictions) prune from the top level with a score actually reached:
    every leaf within keep_ratio of the best discounted score is still returned, with its score,
    whether the seeds are right, wrong or outside the search; a right seed scores fewer nodes."""
    pts, nrm = room_points(rng)
    grid = LikelihoodGrid.from_points(pts, 0.05, 0.05, 2.0, nrm, np.radians(1.0), 0.5)
    truth = np.array([0.9, 0.6, np.radians(-7.0)])
    scan = transform_points(inverse(truth), pts[::9]) + rng.normal(0, 0.01, (len(pts[::9]), 2))
    scan_normals = nrm[::9] - truth[2]
    headings = np.radians(np.concatenate([np.arange(-12.0, -1.0), np.arange(83.0, 94.0)]))  # two rotation candidates

    def discount(poses):  # a motion prior: turns and distance from the origin cost
        return 0.25 * np.abs(poses[:, 2]) / np.pi + 0.05 * np.linalg.norm(poses[:, :2], axis=1)

    matcher = BranchAndBound(grid, 4)
    plain = matcher.search(scan, scan_normals, np.zeros(2), headings, 1.3, 0.0, 0.77, discount)
    for seeds in (truth[None], np.array([[0.0, 0.0, np.radians(90.0)], [-3.0, 5.0, 2.0]]), truth[None] + [0.6, 0, 0]):
        seeded = matcher.search(scan, scan_normals, np.zeros(2), headings, 1.3, 0.0, 0.77, discount, seeds)
        assert np.array_equal(seeded.candidates, plain.candidates) and np.array_equal(seeded.scores, plain.scores)
        assert np.array_equal(seeded.pose, plain.pose)
    assert len(plain.candidates) > 1 and np.abs(plain.pose[:2] - truth[:2]).max() <= 0.05 + 1e-9
    right = matcher.search(scan, scan_normals, np.zeros(2), headings, 1.3, 0.0, 0.77, discount, truth[None])
    assert right.evaluated < plain.evaluated


ARCS = (SlamConfig().scan.arc_range_m, np.radians(SlamConfig().scan.seam_gap_deg))  # arc range, seam gap


def arc_scan(normal_deg: float, rng) -> Scan:
    """A wall seen as an arc: beams of orientation 0 at one range, power peaking on the normal."""
    beams = np.arange(-6, 7)
    angle = np.arcsin(2 * beams / 64)
    power = -0.5 * ((np.degrees(angle) - normal_deg) / 2.0) ** 2
    power -= power.max()
    return Scan(np.full(len(beams), 4.0), angle, power, beams, np.zeros(len(beams), np.int64))


@pytest.mark.parametrize("normal_deg", [-2.3, 0.0, 0.7, 3.1])
def test_specular_normal_is_the_vertex_of_the_arc_power(normal_deg, rng):
    normals = specular_normals(arc_scan(normal_deg, rng), *ARCS)
    assert np.allclose(np.degrees(normals), normal_deg, atol=1e-6)  # a parabola in dB is fitted exactly


def test_points_of_a_run_without_interior_peak_have_no_normal(rng):
    scan = arc_scan(20.0, rng)  # the peak lies beyond the last beam
    assert np.isnan(specular_normals(scan, *ARCS)).all()


def seam_scan(normal_deg: float) -> Scan:
    """A wall near 45°, between orientation 0's sector (beams to 46°) and orientation 1's (from 44°):
    the last beams of each, at one range, the power a parabola in bearing around the normal."""
    beams = np.arange(14, 24)
    angle = np.concatenate([np.arcsin(2 * beams / 64), np.pi / 2 - np.arcsin(2 * beams / 64)])
    power = -0.5 * ((np.degrees(angle) - normal_deg) / 2.0) ** 2
    return Scan(np.full(2 * len(beams), 4.0), angle, power - power.max(), np.concatenate([beams, -beams]),
                np.repeat([0, 1], len(beams)))


@pytest.mark.parametrize("normal_deg", [44.8, 45.0, 45.2])
def test_a_wall_between_two_sectors_takes_the_normal_of_both_arcs_together(normal_deg):
    """Each orientation's arc peaks on its last beam (no interior peak: no normal before, so a terminal
    held at 45° to a room had no normal on any wall and stood still while walking, rectangle-fixed-4031
    2.1 m); fitted together, the two arcs give the normal and one sighting of the wall."""
    normals, sightings = specular_arcs(seam_scan(normal_deg), *ARCS)
    assert np.allclose(np.degrees(normals), normal_deg, atol=1e-6)  # a parabola in dB is fitted exactly
    assert len(sightings) == 1 and np.isclose(np.degrees(sightings[0, 0]), normal_deg, atol=1e-6)


def test_only_two_edge_arcs_are_fitted_together():
    """The normal at 41° peaks inside orientation 0's sector: that arc is fitted alone, and orientation
    1's arc of the wall, peaking on its edge (44°), keeps no normal (taking the interior arc's was
    tried: such an arc is often another surface's). Two edge arcs at different ranges, or farther than
    ``seam_gap_deg`` apart, are two surfaces: no normal."""
    arc_range = ARCS[0]
    scan = seam_scan(41.0)
    normals, sightings = specular_arcs(scan, *ARCS)
    assert np.allclose(np.degrees(normals[scan.orientation == 0]), 41.0, atol=1e-6) and len(sightings) == 1
    assert np.isnan(normals[scan.orientation == 1]).all()
    scan = seam_scan(45.0)
    apart = Scan(np.where(scan.orientation == 1, 5.0, 4.0), scan.angle_rad, scan.power_db, scan.beam,
                 scan.orientation)
    assert np.isnan(specular_arcs(apart, *ARCS)[0]).all()
    assert np.isnan(specular_arcs(scan, arc_range, np.radians(1.0))[0]).all()  # peaks 2° apart


def synthetic_scans(poses, walls_pts, walls_nrm, rng, max_range=6.0):
    """Scans of world points as seen from each pose (within ``max_range``)."""
    scans = []
    for pose in poses:
        local = transform_points(inverse(pose), walls_pts)
        keep = np.linalg.norm(local, axis=1) < max_range
        xy = local[keep] + rng.normal(0, 0.005, (keep.sum(), 2))
        scans.append(Scan(np.linalg.norm(xy, axis=1), np.arctan2(xy[:, 1], xy[:, 0]), np.zeros(keep.sum()),
                          np.zeros(keep.sum(), np.int64), np.zeros(keep.sum(), np.int64)))
    return scans


def test_scan_with_too_few_points_is_skipped_and_the_trajectory_continues(rng):
    pts, nrm = room_points(rng, 600)
    poses = np.array([[-1.0 + 0.2 * k, 0.5, 0.0] for k in range(8)])
    scans = synthetic_scans(poses, pts, nrm, rng)
    scans[4] = Scan.empty()
    result = RadioSlam(SlamConfig()).run(scans)
    assert [s is ScanStatus.SKIPPED for s in result.status] == [k == 4 for k in range(8)]
    assert any("scan 4" in w and "skipped" in w for w in result.warnings)
    rel = between(result.poses[0], result.poses)
    truth = between(poses[0], poses)
    assert np.abs(rel[:, :2] - truth[:, :2]).max() < 0.1  # the skipped pose is interpolated by the motion model


def test_weak_direction_is_the_one_no_surface_constrains(rng):
    """Zhang et al. 2016: J = Σ n nᵀ over the points' normals; its null space is unobserved."""
    from radioslam.slam.degeneracy import line_normals, remap
    from radioslam.slam.degeneracy import weak_direction as weak_of

    def weak_direction(xy, normals, heading, cov, ratio):
        return weak_of(xy, normals, heading, cov, ratio, 0.5, 6)

    tight = np.diag([1e-4, 1e-4, 1e-6])
    xy = rng.normal(0, 3, (6, 2))
    room = np.array([0.0, 0.0, np.pi / 2, np.pi / 2, np.nan, np.nan])  # two arcs at right angles
    assert weak_direction(xy, room, 0.3, tight, 4.0) is None
    corridor = np.array([np.pi / 2, np.pi / 2, -np.pi / 2, -np.pi / 2, np.nan, np.nan])
    far = np.array([[0, 0], [0, 2], [3, 0], [3, 2], [20, 0], [-20, 0]])  # the unknown ones isolated
    weak = weak_direction(far, corridor, 0.3, tight, 4.0)
    assert abs(abs(weak @ [np.cos(0.3), np.sin(0.3)]) - 1) < 1e-9  # along the corridor, in the world frame
    # points without a specular normal lend the normal of the line through their neighbours
    wall = np.column_stack([np.linspace(0, 0.5, 6), np.linspace(0, 1, 6)])
    assert np.allclose(np.tan(line_normals(wall, 0.5, 6) - np.pi / 2), 2.0)
    assert weak_direction(np.vstack([far, wall + [0, 5]]), np.concatenate([corridor, np.full(6, np.nan)]), 0.0,
                          tight, 4.0) is None  # a steep wall fixes the corridor's axis
    # the match's own covariance, elongated 10:1 along y, is the other trigger
    assert abs(weak_direction(xy, room, 0.0, np.diag([1e-4, 1e-2, 1e-6]), 4.0)[1]) == pytest.approx(1)
    pose, cov = remap(np.array([1.0, 2.0, 0.1]), tight, np.array([3.0, 5.0, 0.0]), np.array([1.0, 0.0]), 0.5)
    assert pose == pytest.approx([3.0, 2.0, 0.1])  # x from the prediction, y and θ from the match
    assert cov[0, 0] == pytest.approx(0.25 + 1e-4) and cov[1, 1] == pytest.approx(1e-4)


def test_featureless_corridor_is_flagged_degenerate():
    """Simulated radio scans of a long straight corridor: each wall is an arc at the
    perpendicular foot, the same at every pose, so nothing fixes the motion along it."""
    from radioslam.scene.loader import scene_from_mapping
    from radioslam.sensing import Receiver
    from radioslam.sim import Simulator

    scene = scene_from_mapping({
        "version": 1, "name": "corridor",
        "walls": [{"points": [[-60.0, 2.0], [60.0, 2.0]], "material": "concrete"},
                  {"points": [[-60.0, -2.0], [60.0, -2.0]], "material": "concrete"}],
        "trajectory": {"poses": [[0.4 * k, 0.0, 0.0] for k in range(5)]},
    }, "test:corridor")
    receiver = Receiver(scene.radio, scene.radio.hardware_delay_s)
    scans = [receiver.sense(c).scan for c in Simulator.from_scene(scene).simulate(3)]
    result = RadioSlam(SlamConfig()).run(scans)
    assert all(s is ScanStatus.DEGENERATE for s in result.status[1:])
    flagged = [w for w in result.warnings if "degenerate match" in w]
    assert "4 scan(s) degenerate: 1–4" in result.summary_lines()
    assert len(flagged) == 4 and all(w.endswith(("along 0° (predicted instead)", "along 180° (predicted instead)",
                                                   "along -180° (predicted instead)")) for w in flagged)
    # what the walls do fix stays right: the lateral position and the heading
    assert np.abs(result.poses[:, 1]).max() < 0.05 and np.abs(result.poses[:, 2]).max() < np.radians(0.5)


def test_a_wall_the_map_lacks_fixes_nothing():
    """Only the points that agree with the map count towards the match's information: a
    wall seen for the first time cannot stop the match sliding along the one in common."""
    from radioslam.slam.degeneracy import DegeneracyTest

    def matched_weak_direction(grid, pose, scan, normals, cov, ratio):
        return DegeneracyTest(ratio, 0.5, 6, 2.0).matched_weak(grid, pose, scan, normals, cov)

    along = np.column_stack([np.linspace(-3, 3, 61), np.full(61, 2.0)])  # a wall y = 2, normal −90°
    across = np.column_stack([np.full(41, 4.0), np.linspace(-2, 2, 41)])  # a wall x = 4, normal 180°
    scan = np.vstack([along, across])
    normals = np.concatenate([np.full(61, -np.pi / 2), np.full(41, np.pi)])
    tight = np.diag([1e-4, 1e-4, 1e-6])
    pose = np.zeros(3)
    one_wall = LikelihoodGrid.from_points(along, 0.05, 0.05, 1.0, np.full(61, -np.pi / 2), np.radians(1.0), 0.5)
    weak = matched_weak_direction(one_wall, pose, scan, normals, tight, 4.0)
    assert weak is not None and abs(weak[0]) == pytest.approx(1.0)
    both = LikelihoodGrid.from_points(scan, 0.05, 0.05, 1.0, normals, np.radians(1.0), 0.5)
    assert matched_weak_direction(both, pose, scan, normals, tight, 4.0) is None


def test_a_match_slid_along_its_walls_is_settled_by_the_wall_facing_along_them():
    """The terminal stepped 0.6 m along a wall toward a wall across its path, and the match kept it
    still: the across wall's points, 0.6 m off, disagree and drop out of the information, so the
    match looks degenerate along the walk. Slid along that direction to where the points facing it
    fit, the match is no longer degenerate; with the across wall not in the map, nothing settles it."""
    from radioslam.slam.degeneracy import DegeneracyTest

    test = DegeneracyTest(4.0, 0.5, 6, 2.0)
    along = np.column_stack([np.linspace(-3, 3, 61), np.full(61, 2.0)])  # a wall y = 2, normal −90°
    across = np.column_stack([np.full(41, 4.0), np.linspace(-2, 2, 41)])  # a wall x = 4, normal 180°
    normals = np.concatenate([np.full(61, -np.pi / 2), np.full(41, np.pi)])
    both = LikelihoodGrid.from_points(np.vstack([along, across]), 0.05, 0.05, 1.0, normals, np.radians(1.0), 0.5)
    scan = np.vstack([along, across]) - [0.6, 0.0]  # seen from (0.6, 0): the along wall looks the same
    tight, still = np.diag([1e-4, 1e-4, 1e-6]), np.zeros(3)
    weak = test.matched_weak(both, still, scan, normals, tight)
    assert weak is not None and abs(weak[0]) == pytest.approx(1.0)
    ones, flat = np.ones(len(scan)), lambda poses: np.zeros(len(poses))
    settled = test.settled(both, still, scan, normals, ones, weak, 1.3, flat)
    assert settled == pytest.approx([0.6, 0.0, 0.0], abs=0.05 + 1e-9)  # within a cell: trials a cell apart
    assert test.matched_weak(both, settled, scan, normals, tight) is None
    # standing still is no rival of the settled match: the across wall's points tell them apart; a turned
    # rival they do not judge, and without the across wall in the map nothing tells standing still apart
    rivals = np.array([still, settled + [0.0, 0.0, 0.5]])
    assert test.told_apart(both, settled, scan, normals, rivals, 0.08, np.radians(6.0)).tolist() == [True, False]
    one_wall = LikelihoodGrid.from_points(along, 0.05, 0.05, 1.0, np.full(61, -np.pi / 2), np.radians(1.0), 0.5)
    assert test.settled(one_wall, still, scan, normals, ones, weak, 1.3, flat) is None
    assert test.told_apart(one_wall, settled, scan, normals, rivals[:1], 0.08, np.radians(6.0)).tolist() == [False]


def test_a_slide_along_the_walls_is_the_posterior_s_the_facing_echoes_against_the_motion():
    """The settle weighs the echoes that face along the slide against the motion's prior of the step: the
    across wall seen as one echo (its arc's 41 points weighing 1/41 each: a few nats at most) does not move a
    robot 0.6 m off a step it predicted to 10 cm (18 nats); the same wall as 41 independent echoes does, and
    so does the one echo where the motion says nothing."""
    from radioslam.slam.degeneracy import DegeneracyTest
    from radioslam.slam.motion_prior import PLATFORMS, MotionPrior, Platform

    test = DegeneracyTest(4.0, 0.5, 6, 2.0)
    along = np.column_stack([np.linspace(-3, 3, 61), np.full(61, 2.0)])
    across = np.column_stack([np.full(41, 4.0), np.linspace(-2, 2, 41)])
    normals = np.concatenate([np.full(61, -np.pi / 2), np.full(41, np.pi)])
    both = LikelihoodGrid.from_points(np.vstack([along, across]), 0.05, 0.05, 1.0, normals, np.radians(1.0), 0.5)
    scan, still, weak = np.vstack([along, across]) - [0.6, 0.0], np.zeros(3), np.array([1.0, 0.0])
    robot = MotionPrior.of(np.zeros((1, 3)), PLATFORMS[Platform.ROBOT], 1.3)  # the step predicted: none
    one_echo = np.concatenate([np.full(61, 1 / 61), np.full(41, 1 / 41)])
    assert test.settled(both, still, scan, normals, one_echo, weak, 1.3, robot.log_prob) is None
    independent = test.settled(both, still, scan, normals, np.ones(len(scan)), weak, 1.3, robot.log_prob)
    assert independent == pytest.approx([0.6, 0.0, 0.0], abs=0.05 + 1e-9)
    unknown = test.settled(both, still, scan, normals, one_echo, weak, 1.3, lambda poses: np.zeros(len(poses)))
    assert unknown == pytest.approx([0.6, 0.0, 0.0], abs=0.05 + 1e-9)


def test_pace_is_the_median_observed_step_along_the_predicted_travel():
    from radioslam.slam.motion import pace_prediction

    last, prediction = np.array([1.0, 1.0, 0.0]), np.array([1.0, 1.4, 0.05])
    paced = pace_prediction(prediction, last, [0.5, 0.6, 0.5, 9.0], 3)
    assert paced == pytest.approx([1.0, 1.6, 0.05])  # median of the last three lengths, heading kept
    assert pace_prediction(prediction, last, [], 3) is prediction  # nothing observed yet
    assert pace_prediction(last.copy(), last, [0.5], 3) == pytest.approx(last)  # standing still stays still


def test_match_the_map_does_not_support_keeps_the_prediction(rng):
    """A scan whose points the local map cannot explain (a wholly new view) must not move
    the pose: the scan is predicted (one alone is not a lost stretch) and the motion model's pose kept."""
    pts, nrm = room_points(rng, 600)
    poses = np.array([[-1.0 + 0.2 * k, 0.5, 0.0] for k in range(8)])
    scans = synthetic_scans(poses, pts, nrm, rng)
    elsewhere = rng.uniform(-5, 5, (60, 2)) + [40.0, 0.0]  # points of no wall in the map
    scans[4] = Scan(np.linalg.norm(elsewhere, axis=1), np.arctan2(elsewhere[:, 1], elsewhere[:, 0]),
                    np.zeros(60), np.zeros(60, np.int64), np.zeros(60, np.int64))
    result = RadioSlam(SlamConfig()).run(scans)
    assert [s is ScanStatus.PREDICTED for s in result.status] == [k == 4 for k in range(8)]
    assert result.match_score[4] < SlamConfig().front_end.min_match_score
    assert any(w.startswith("scan 4: match score") for w in result.warnings)
    assert not result.tracking_lost  # one predicted scan between matched ones is a new view
    rel = between(result.poses[0], result.poses)
    assert np.abs(rel[:, :2] - between(poses[0], poses)[:, :2]).max() < 0.05


def test_an_arc_on_a_nearer_wall_line_is_that_wall_seen_obliquely():
    """A wall of normal ψ = −39° with its foot at 2.41 m is met by the beam at θ at 2.41 / cos(θ − ψ):
    arcs there (at −16° and −66°, 2.63 m) are that wall, and carry its normal; an arc of another wall
    (a corner's second wall at 4.4 m, normal 25°) and the wall itself keep theirs."""
    psi, rho = np.radians(-39.0), 2.41
    bearing = np.radians(np.array([-39.0, -16.0, -66.0, 25.0]))
    foot = np.array([rho, rho / np.cos(np.radians(23.0)), rho / np.cos(np.radians(27.0)), 4.42])
    assert oblique_walls(bearing, foot, 0.10).tolist() == [-1, 0, 0, -1]
    assert np.isclose(bearing[0], psi)
    # off the line by more than the tolerance (a parallel wall 0.3 m behind): its own wall
    assert oblique_walls(bearing[:2], foot[:2] + [0.0, 0.3], 0.10).tolist() == [-1, -1]
    assert oblique_walls(np.zeros(0), np.zeros(0), 0.10).tolist() == []


def test_pose_graph_marginals_grow_along_an_open_chain_and_a_kept_loop_shrinks_them():
    """``PoseGraph.marginal_sigmas``: along an open chain of steps each pose is known less well than
    the one before (the first is the prior's); a loop back to the start that the solution keeps fixes
    the far end again; a loop far outside the χ² gate at the solution (one GNC rejects) fixes nothing."""
    from radioslam.slam.pose_graph import PoseGraph
    from radioslam.slam.se2 import between, pose_covariance

    n, step_cov = 24, pose_covariance(0.02, 0.3)
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    truth = np.stack([3 * np.cos(t), 3 * np.sin(t), t + np.pi / 2], axis=1)

    def chain() -> PoseGraph:
        graph = PoseGraph()
        for k in range(n):
            graph.add_pose(k, truth[k])
            if k:
                graph.add_odometry(k - 1, k, between(truth[k - 1], truth[k]), step_cov)
        return graph

    open_chain = chain().marginal_sigmas(16.27)
    heading = np.array([open_chain[k][2] for k in range(n)])
    position = np.array([np.hypot(*open_chain[k][:2]) for k in range(n)])
    assert heading[0] < 1e-4 and np.all(np.diff(heading) > 0)
    assert position[-1] > 5 * np.hypot(0.02, 0.02)  # the heading's spread carried over the distance walked
    closed = chain()
    closed.add_loop(0, n - 1, between(truth[0], truth[n - 1]), step_cov)
    closed.optimize()
    assert np.hypot(*closed.marginal_sigmas(16.27)[n - 1][:2]) < 0.3 * position[-1]
    rejected = chain()
    rejected.add_loop(0, n - 1, between(truth[0], truth[n - 1]) + np.array([2.0, 0.0, 0.0]), step_cov)
    sigmas = rejected.marginal_sigmas(16.27)  # at the chain's poses: the loop's χ² is far outside the gate
    assert np.allclose([sigmas[k] for k in range(n)], [open_chain[k] for k in range(n)])


def test_the_back_end_solves_incrementally_and_the_batch_solve_decides_only_a_doubtful_loop():
    """Issue #14: the back end's incremental solution (iSAM2) after each loop equals the batch
    Levenberg–Marquardt solution of the same graph; a consistent loop never calls the robust batch
    solve; a wrong loop (2 m off) leaves a residual beyond GNC's inlier threshold there, so the batch
    solve runs, rejects it, and the trajectory is the one without it."""
    from radioslam.slam.back_end import BackEnd
    from radioslam.slam.front_end import Step
    from radioslam.slam.loop_closer import LoopClosure
    from radioslam.slam.se2 import between, compose, pose_covariance

    rng = np.random.default_rng(3)
    n, step_cov, loop_cov = 40, pose_covariance(0.01, 0.2), pose_covariance(0.03, 0.5)
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    truth = np.stack([3 * np.cos(t), 3 * np.sin(t), t + np.pi / 2], axis=1)

    def walk(loop_offsets: dict[int, np.ndarray]) -> BackEnd:
        back_end, pose = BackEnd.from_config(SlamConfig()), truth[0]
        for k in range(n):
            if k:
                noisy = between(truth[k - 1], truth[k]) + rng.normal(0, [0.01, 0.01, np.radians(0.2)])
                pose = compose(back_end.estimates[k - 1], noisy)
            back_end.add(k, Step(pose, step_cov, ScanStatus.MATCHED))
            if k in loop_offsets:  # scan k seen again from scan 0's submap
                relative = compose(between(truth[0], truth[k]), loop_offsets[k])
                back_end.add_loops([LoopClosure(0, k, relative, loop_cov, 0.9)])
        back_end.finish()
        return back_end

    def batch(back_end: BackEnd) -> np.ndarray:
        back_end.graph.move(back_end.estimates)
        return np.array([back_end.graph.optimize(robust=False)[0][k] for k in range(n)])

    consistent = walk({k: np.zeros(3) for k in (30, 35, 39)})
    incremental = np.array([consistent.estimates[k] for k in range(n)])
    assert consistent.batch_solves == 0
    assert np.abs(incremental - batch(consistent)).max() < 1e-5
    assert np.abs(incremental[-1, :2] - truth[-1, :2]).max() < 0.05  # the loops pulled the end back
    rng = np.random.default_rng(3)
    spoiled = walk({30: np.zeros(3), 35: np.array([2.0, 0.0, 0.0]), 39: np.zeros(3)})
    assert spoiled.batch_solves >= 1
    rng = np.random.default_rng(3)
    without = walk({30: np.zeros(3), 39: np.zeros(3)})
    assert np.abs(np.array([spoiled.estimates[k] - without.estimates[k] for k in range(n)])).max() < 1e-3


def test_the_odometry_drift_between_two_poses_is_the_sum_of_the_steps_between_them():
    """The loop gate's drift (running sums of the step covariances, O(1) a loop) equals the step
    covariances from the anchor's successor to the scan summed, with the heading's variance spreading
    the position by the distance, and follows a step the front end did not see (a cut: the jump's)."""
    from radioslam.slam.back_end import BackEnd
    from radioslam.slam.front_end import Step

    rng = np.random.default_rng(5)
    back_end = BackEnd.from_config(SlamConfig())
    for k in range(12):
        a = rng.normal(size=(3, 3))
        back_end.add(k, Step(np.array([0.5 * k, 0.0, 0.1 * k]), a @ a.T + np.eye(3), ScanStatus.MATCHED))

    def summed(anchor: int, key: int) -> np.ndarray:
        return sum(back_end.step_covariance[m] for m in range(anchor + 1, key + 1))

    for anchor, key, distance in ((0, 11, 3.0), (4, 7, 1.5), (10, 11, 0.0)):
        total = summed(anchor, key)
        expected = total + np.diag([total[2, 2] * distance**2] * 2 + [0.0])
        assert np.allclose(back_end.drift(anchor, key, distance), expected, rtol=1e-12, atol=1e-12)
    back_end.cut(6)
    assert np.allclose(back_end.step_covariance[6], back_end.jump_covariance)
    assert np.allclose(back_end.drift(2, 9, 0.0), summed(2, 9), rtol=1e-12, atol=1e-12)
    back_end.add(12, Step(np.array([6.0, 0.0, 1.2]), np.eye(3), ScanStatus.MATCHED))
    assert np.allclose(back_end.drift(5, 12, 0.0), summed(5, 12), rtol=1e-12, atol=1e-12)


def test_a_submaps_matcher_is_kept_while_its_scans_stay_put_relative_to_its_first():
    """Cartographer keeps a finished submap's grid: a new pose-graph solution that carries the whole
    submap rigidly, or moves its scans less than half a cell against its first one, keeps the matcher
    (its grid and pyramid); a scan moved by more (a fork's switch, a cut) builds it again."""
    from radioslam.slam.loop_closer import LoopCloser
    from radioslam.slam.scan_points import ScanPoints
    from radioslam.slam.se2 import compose

    cfg = SlamConfig()
    closer = LoopCloser.from_config(cfg)
    wall = np.column_stack([np.full(30, 3.0), np.linspace(-1.5, 1.5, 30)])
    for k in range(cfg.loop_closure.submap_scans):
        closer.keyframes.insert(k, ScanPoints(wall, np.full(30, np.pi), np.zeros((0, 2))))
    submap = closer.keyframes.submaps[0]
    estimates = {k: np.array([0.3 * k, 0.0, 0.0]) for k in submap.keys}
    first = closer._pyramid(submap, estimates, 2.0)
    carried = {k: compose([5.0, -2.0, 0.7], p) for k, p in estimates.items()}  # the whole submap moved rigidly
    assert closer._pyramid(submap, carried, 2.0) is first
    nudged = {**carried, 3: compose(carried[3], [0.01, 0.0, np.radians(0.1)])}  # a centimetre: within half a cell
    assert closer._pyramid(submap, nudged, 2.0) is first
    moved = {**carried, 3: compose(carried[3], [0.04, 0.0, 0.0])}  # beyond half a cell
    rebuilt = closer._pyramid(submap, moved, 2.0)
    assert rebuilt is not first
    assert closer._pyramid(submap, moved, 2.0) is rebuilt


def test_at_most_cached_matchers_are_kept_the_least_recently_used_dropped():
    """A submap's matcher is 8–11 MB (its grid covers the whole room a radio scan sees): at most
    ``cached_matchers`` are kept; the least recently used one goes and is built again when needed."""
    from radioslam.slam.loop_closer import LoopCloser
    from radioslam.slam.scan_points import ScanPoints

    cfg = SlamConfig(loop_closure={"cached_matchers": 2, "submap_scans": 1})
    closer = LoopCloser.from_config(cfg)
    wall = np.column_stack([np.full(30, 3.0), np.linspace(-1.5, 1.5, 30)])
    for k in range(3):
        closer.keyframes.insert(k, ScanPoints(wall, np.full(30, np.pi), np.zeros((0, 2))))
    estimates = {k: np.array([0.3 * k, 0.0, 0.0]) for k in range(3)}
    first, second = (closer._pyramid(closer.keyframes.submaps[i], estimates, 2.0) for i in (0, 1))
    assert closer._pyramid(closer.keyframes.submaps[0], estimates, 2.0) is first  # used again: now the most recent
    closer._pyramid(closer.keyframes.submaps[2], estimates, 2.0)  # a third: the least recently used (the second) goes
    assert sorted(closer.pyramids) == [0, 2]
    assert closer._pyramid(closer.keyframes.submaps[1], estimates, 2.0) is not second


def test_loop_search_matches_a_few_submaps_a_scan_those_tried_longest_ago_first():
    """A place walked many times has a candidate submap from every lap: each scan is matched against
    at most ``loop_matches_per_scan`` of them (a flat cost per scan), those never tried first, then those
    whose matchers are kept, then the others, each group those tried longest ago first, then the nearest:
    consecutive scans tie in every lap's submaps in turn, and a dropped matcher is built again only when
    nothing kept is near. Scans just after one that closed a loop search only every ``tied_search_every``."""
    from radioslam.slam.loop_closer import LoopCloser
    from radioslam.slam.scan_points import ScanPoints

    cfg = SlamConfig()
    lc = cfg.loop_closure
    closer = LoopCloser.from_config(cfg)
    empty = ScanPoints(np.zeros((0, 2)), np.zeros(0), np.zeros((0, 2)))
    laps, per = 7, lc.submap_scans
    estimates = {}
    for k in range((laps + lc.skip_submaps + 1) * per):  # submaps 0 … laps − 1 at the place, then the latest
        closer.keyframes.insert(k, empty)
        lap = k // per
        estimates[k] = np.array([0.1 * lap, 0.0, 0.0]) if lap < laps else np.array([50.0 + k, 0.0, 0.0])
    here, budget = np.zeros(3), lc.loop_matches_per_scan
    first = [s.anchor for s in closer._candidates(here, estimates, budget)]
    assert len(first) == lc.loop_matches_per_scan == 3
    assert first == [0, per, 2 * per]  # never tried, the nearest first
    for anchor in first:
        closer.tried[anchor] = 100
    second = [s.anchor for s in closer._candidates(here, estimates, budget)]
    assert second == [3 * per, 4 * per, 5 * per]  # the untried ones come next
    for anchor in second:
        closer.tried[anchor] = 101
    third = [s.anchor for s in closer._candidates(here, estimates, budget)]
    assert third == [6 * per, 0, per]  # then the ones tried longest ago, nearest first among equals
    closer.tried[6 * per] = 102
    closer.pyramids = {4 * per: None, 6 * per: None}  # kept matchers come before dropped ones
    assert [s.anchor for s in closer._candidates(here, estimates, budget)] == [4 * per, 6 * per, 0]
    assert [s.anchor for s in closer._candidates(here, estimates, 1)] == [4 * per]
    assert closer._candidates(here, estimates, 0) == []
    far = np.array([20.0, 0.0, 0.0])
    assert closer._candidates(far, estimates, budget) == []
    every = lc.tied_search_every
    assert closer.budget(3 * every + 1, None) == closer.budget(3 * every + 1, 2 * every) == budget  # not tied
    assert closer.budget(3 * every + 1, 3 * every) == 0  # tied: only every tied_search_every-th scan searches
    assert closer.budget(3 * every, 3 * every - 1) == budget
