"""Trajectory metrics against evo, map metrics against geometry, file round trips, and the
SLAM run directory end to end on paper-cnv (waveform IQ)."""

import json

import numpy as np
import pytest

from radioslam.eval.map_metrics import map_coverage, map_error
from radioslam.eval.trajectory_metrics import ate_rmse, rpe_rmse
from radioslam.io import read_tum, write_tum
from radioslam.io.ros_map import FREE, OCCUPIED, UNKNOWN, read_ros_map, write_ros_map
from radioslam.slam.config import MapConfig
from radioslam.slam.occupancy import occupancy_grid
from radioslam.slam.se2 import compose


def test_ate_equals_evo_ape_aligned_within_a_millimetre(tmp_path, rng):
    from evo.core import metrics, sync
    from evo.tools import file_interface

    phi = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    truth = np.column_stack([5 * np.cos(phi), 5 * np.sin(phi), phi + np.pi / 2])
    noisy = truth + rng.normal(0, [0.05, 0.05, 0.01], truth.shape)
    estimate = compose(np.array([1.0, -2.0, 0.7]), noisy)  # another frame: alignment must undo it
    t = np.arange(len(truth), dtype=float)
    write_tum(tmp_path / "gt.tum", t, truth)
    write_tum(tmp_path / "est.tum", t, estimate)
    ref = file_interface.read_tum_trajectory_file(str(tmp_path / "gt.tum"))
    est = file_interface.read_tum_trajectory_file(str(tmp_path / "est.tum"))
    ref, est = sync.associate_trajectories(ref, est)
    est.align(ref, correct_scale=False)
    ape = metrics.APE(metrics.PoseRelation.translation_part)
    ape.process_data((ref, est))
    assert ate_rmse(estimate, truth) == pytest.approx(ape.get_statistic(metrics.StatisticsType.rmse), abs=1e-3)
    rpe = metrics.RPE(metrics.PoseRelation.translation_part, delta=1, delta_unit=metrics.Unit.frames, all_pairs=False)
    rpe.process_data((ref, est))
    assert rpe_rmse(estimate, truth) == pytest.approx(rpe.get_statistic(metrics.StatisticsType.rmse), abs=1e-3)


def test_map_metrics_of_points_on_and_off_a_wall():
    square = np.array([[[0, 0], [4, 0]], [[4, 0], [4, 4]], [[4, 4], [0, 4]], [[0, 4], [0, 0]]], float)
    above_bottom = np.column_stack([np.linspace(0.5, 3.5, 301), np.full(301, 0.1)])
    assert map_error(above_bottom, square) == pytest.approx(0.1, abs=1e-9)
    # the bottom wall from 0.5 − √(0.3² − 0.1²) to 3.5 + √(0.3² − 0.1²), of 16 m of wall
    expected = (3.0 + 2 * np.sqrt(0.3**2 - 0.1**2)) / 16
    assert map_coverage(above_bottom, square) == pytest.approx(expected, abs=0.005)


def test_occupancy_grid_round_trips_through_map_server_files(tmp_path):
    poses = np.zeros((5, 3))  # five looks: enough misses to call a cell free (p < 0.196)
    wall = np.column_stack([np.full(81, 3.0), np.linspace(-1, 1, 81)])
    grid = occupancy_grid(poses, [wall] * 5, MapConfig())
    write_ros_map(tmp_path / "map.yaml", grid)
    cells, meta = read_ros_map(tmp_path / "map.yaml")
    assert meta["image"] == "map.pgm" and meta["resolution"] == 0.05 and meta["origin"][:2] == list(grid.origin)
    wall_cell = np.floor((np.array([3.0, 0.0]) - grid.origin) / 0.05).astype(int)
    free_cell = np.floor((np.array([1.5, 0.0]) - grid.origin) / 0.05).astype(int)
    behind = np.floor((np.array([3.5, 0.0]) - grid.origin) / 0.05).astype(int)
    assert cells[tuple(wall_cell)] == OCCUPIED
    assert cells[tuple(free_cell)] == FREE
    assert cells[tuple(behind)] == UNKNOWN
    # map_server's image has its first row at the top (largest y)
    raw = (tmp_path / "map.pgm").read_bytes().split(b"\n", 4)[4]
    width = cells.shape[0]
    assert raw[:width] == cells[:, -1].astype(np.uint8).tobytes()


def test_demo_meets_its_targets_on_seed_1(demo_run):
    out, m = demo_run
    assert m["ate_rmse_m"] <= 0.10
    # the walls sighted by the specular arcs fix the poses (plane adjustment): well ahead of the front end
    assert m["ate_rmse_m"] <= 0.5 * m["ate_rmse_odometry_m"]
    assert m["loop_closures"] >= 1
    assert m["map_error_m"] <= 0.25
    assert m["map_coverage"] >= 0.7
    assert m["poses"] == 60
    assert json.loads((out / "metrics.json").read_text()) == m


def test_run_directory_files_are_complete_and_consistent(demo_run):
    out, m = demo_run
    t, est = read_tum(out / "trajectory.tum")
    _, odo = read_tum(out / "trajectory_odometry.tum")
    assert len(t) == len(est) == len(odo) == 60
    assert np.allclose(est[0], 0) and np.allclose(odo[0], 0)  # the first scan defines the map frame
    cells, meta = read_ros_map(out / "map.yaml")
    assert (cells == OCCUPIED).sum() > 100 and (cells == FREE).sum() > 1000
    from radioslam.io.ply import read_map_points

    assert len(read_map_points(out / "map.ply")) == round(m["points_per_scan"] * 60)  # every scan's points
    assert not list(out.glob(".*.tmp"))  # no half-written file left behind


def test_the_plane_adjustment_finds_the_rooms_walls(demo_run):
    """slam.json lists the walls of the last solve in the map frame: paper-cnv's 16 m square room is
    two pairs of opposite walls (normal bearings 180° apart) whose offsets add up to 16 m."""
    out, _ = demo_run
    planes = json.loads((out / "slam.json").read_text())["plane_adjustment"]
    walls = np.array(planes["walls"])
    assert planes["sightings_used"] >= 0.5 * planes["sightings"] > 0
    opposite = np.abs(((walls[:, None, 0] - walls[None, :, 0]) % 360) - 180) < 1.0
    width = walls[:, None, 1] + walls[None, :, 1]
    pairs = np.argwhere(opposite & (np.abs(width - 16.0) < 0.05))
    assert len({tuple(sorted(p)) for p in pairs}) >= 2


def test_a_ray_never_clears_a_cell_another_scan_saw_occupied():
    """Issue #12 point 8: a beam is ~13° wide; the ray to the far wall passes a near obstacle that
    other scans saw. The obstacle's cell stays occupied, the ray stops short of its own echo, and
    the space before it is free."""
    far_wall = np.column_stack([np.full(41, 6.0), np.linspace(-1, 1, 41)])
    obstacle = np.array([[3.0, 0.0]])
    poses = np.zeros((6, 3))
    scans = [far_wall] * 5 + [obstacle]  # five looks through the obstacle's cell, one look at it
    grid = occupancy_grid(poses, scans, MapConfig())
    cell = tuple(np.floor((obstacle[0] - grid.origin) / 0.05).astype(int))
    assert grid.probability[cell] > 0.65  # occupied: what a point showed stays
    before = tuple(np.floor((np.array([5.85, 0.0]) - grid.origin) / 0.05).astype(int))
    assert grid.log_odds[before] == 0  # within free_stop_m of the echo: not cleared
    assert grid.probability[tuple(np.floor((np.array([1.5, 0.0]) - grid.origin) / 0.05).astype(int))] < 0.196


@pytest.fixture(scope="module")
def two_laps():
    """paper-cnv's room walked twice (48 poses on a 5 m circle, then 48 on 4.6 m): the second
    lap closes dozens of loops. Simulated and sensed in memory, seed 4."""
    import yaml

    from radioslam.scene import scene_to_yaml
    from radioslam.scene.builtin import paper_cnv
    from radioslam.scene.loader import scene_from_mapping
    from radioslam.sensing import Receiver
    from radioslam.sim import Simulator

    spec = yaml.safe_load(scene_to_yaml(paper_cnv()))
    phi = 2 * np.pi * np.arange(48) / 48
    spec["trajectory"] = {"poses": [[r * np.cos(p), r * np.sin(p), float(np.angle(np.exp(1j * (p + np.pi / 2))))]
                                    for r in (5.0, 4.6) for p in phi]}
    scene = scene_from_mapping(spec, "test:two-laps")
    receiver = Receiver(scene.radio, scene.radio.hardware_delay_s)
    return scene.poses, [receiver.sense(c).scan for c in Simulator.from_scene(scene).simulate(4)]


@pytest.mark.parametrize("robust", [True, False])
def test_false_loop_closures_do_not_spoil_the_optimized_trajectory(two_laps, robust):
    """Issue #4: with every fifth loop closure (20 %) replaced by a wrong one (up to 1.5 m and
    30° off), the GNC pose graph keeps the ATE within 1.5× the clean run's; without GNC the
    same corruption ruins it (so the test can fail)."""
    from dataclasses import replace

    from radioslam.slam import RadioSlam, SlamConfig
    from radioslam.slam.se2 import compose

    truth, scans = two_laps
    rng = np.random.default_rng(0)
    seen = []

    def corrupt(loop):
        seen.append(loop)
        if (len(seen) - 1) % 5:
            return loop
        wrong = rng.uniform(-1, 1, 3) * [1.5, 1.5, np.radians(30.0)]
        return replace(loop, relative=compose(loop.relative, wrong))

    cfg = SlamConfig(pose_graph={"gnc": robust})
    clean = RadioSlam(cfg).run(scans)
    spoiled = RadioSlam(cfg, loop_hook=corrupt).run(scans)
    clean_ate, spoiled_ate = ate_rmse(clean.poses, truth), ate_rmse(spoiled.poses, truth)
    print(f"gnc {robust}: {len(clean.loop_closures)} loops, ATE {clean_ate:.3f} m; "
          f"with {len(seen[::5])} of {len(seen)} wrong, {spoiled_ate:.3f} m")
    assert clean_ate <= 0.10 and len(clean.loop_closures) >= 20
    if robust:
        assert len(seen) >= 20 and spoiled_ate <= 1.5 * clean_ate
    else:
        assert spoiled_ate > 3 * clean_ate


def _cli(*args):
    import subprocess
    import sys

    return subprocess.run([sys.executable, "-m", "radioslam.cli", *args], capture_output=True, text=True, timeout=300)


def _copy(src, dst, *keep):
    import shutil

    dst.mkdir(parents=True, exist_ok=True)
    for name in keep:
        (shutil.copytree if (src / name).is_dir() else shutil.copyfile)(src / name, dst / name)
    return dst


def test_slam_and_evaluate_bad_input_exit_2_with_one_line(demo_run, tmp_path):
    from radioslam.io import write_scan
    from radioslam.sensing import Scan

    out, _ = demo_run
    cases = []
    no_scans = _copy(out, tmp_path / "no-scans", "scene.yaml", "ground_truth.tum")
    cases.append((("slam", str(no_scans)), "scans"))
    empty = _copy(out, tmp_path / "empty", "scene.yaml", "ground_truth.tum", "scans")
    for f in (empty / "scans").glob("*.ply"):
        write_scan(f, Scan.empty())
    cases.append((("slam", str(empty)), "nothing to map"))
    no_traj = _copy(out, tmp_path / "no-trajectory", "scene.yaml", "ground_truth.tum", "scans")
    cases.append((("evaluate", str(no_traj)), "trajectory.tum"))
    nan = _copy(out, tmp_path / "nan", "scene.yaml", "ground_truth.tum", "trajectory.tum", "trajectory_odometry.tum")
    lines = (nan / "trajectory.tum").read_text().splitlines()
    lines[3] = " ".join(lines[3].split()[:1] + ["nan"] + lines[3].split()[2:])
    (nan / "trajectory.tum").write_text("\n".join(lines) + "\n")
    cases.append((("evaluate", str(nan)), "trajectory.tum"))
    for args, fragment in cases:
        done = _cli(*args)
        assert done.returncode == 2, (args, done.stderr)
        assert len(done.stderr.strip().splitlines()) == 1 and "Traceback" not in done.stderr, done.stderr
        assert fragment in done.stderr, done.stderr
    assert not (empty / "trajectory.tum").exists()  # nothing half-written that looks complete


def test_reproduce_fig6_draws_the_figure_and_prints_the_starred_keys(tmp_path):
    done = _cli("reproduce", "fig6", "--out", str(tmp_path), "--json", "--seed", "1")
    assert done.returncode == 0, done.stderr
    doc = json.loads(done.stdout)
    assert {"ate_rmse_m", "ate_rmse_odometry_m", "loop_closures", "map_error_m", "map_coverage"} <= doc.keys()
    assert doc["ate_rmse_m"] <= 0.10
    assert (tmp_path / "fig6.png").stat().st_size > 10_000 and (tmp_path / "fig6.csv").exists()
    assert (tmp_path / "fig6-run" / "report.html").exists()


def test_specular_ranging_errors_are_the_range_minus_the_perpendicular_distance():
    """eval.ranging: in a 10 m × 6 m room, the terminal at (2, 1) turned 30°, echoes of the four walls'
    feet of the perpendicular at their ranges plus known errors give back those errors; a point whose
    beam looks away from every foot, and a ghost 2 m beyond a wall, are left out."""
    from radioslam.eval.ranging import beam_half_width_rad, specular_range_errors

    corners = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 6.0], [0.0, 6.0]])
    walls = np.stack([corners, np.roll(corners, -1, axis=0)], axis=1)
    pose = np.array([2.0, 1.0, np.radians(30.0)])
    world = np.radians([-90.0, 0.0, 90.0, 180.0])  # the feet: below, right, above, left
    distance = np.array([1.0, 8.0, 5.0, 2.0])
    made = np.array([0.003, -0.002, 0.0015, 0.004])
    bearing = np.concatenate([world + np.radians([2.0, -3.0, 1.0, 0.5]), np.radians([45.0, 180.0])]) - pose[2]
    ranges = np.concatenate([distance + made, [3.0, 4.0]])  # then one looking at a corner, one ghost
    errors = specular_range_errors(pose, ranges, bearing, walls, 2 * beam_half_width_rad(8))
    assert np.allclose(np.sort(errors), np.sort(made))
    assert np.degrees(beam_half_width_rad(8)) == pytest.approx(6.35, abs=0.01)


def test_the_robust_ranging_rmse_leaves_out_echoes_of_something_else():
    """eval.ranging.robust_rmse: 200 errors of 1 mm standard deviation and 10 echoes of an obstacle 0.3 m
    before the wall: the RMS of the 200 alone (within 3 robust standard deviations), counted as 200."""
    from radioslam.eval.ranging import robust_rmse

    rng = np.random.default_rng(4)
    clean = rng.normal(0.0, 1e-3, 200)
    rmse, kept = robust_rmse(np.concatenate([clean, np.full(10, -0.3)]))
    assert kept == 200 and rmse == pytest.approx(np.sqrt(np.mean(clean**2)))
    assert robust_rmse(np.zeros(0)) == (None, 0)
