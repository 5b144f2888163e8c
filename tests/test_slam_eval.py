"""Trajectory metrics against evo, map metrics against geometry, file round trips, and the
SLAM run directory end to end on paper-cnv (waveform IQ)."""

import json

import numpy as np
import pytest

from radioslam.eval.map_metrics import map_coverage, map_error
from radioslam.eval.trajectory_metrics import ate_rmse, rpe_rmse
from radioslam.io import read_tum, write_tum
from radioslam.io.ros_map import FREE, OCCUPIED, UNKNOWN, read_ros_map, write_ros_map
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
    grid = occupancy_grid(poses, [wall] * 5, 0.05)
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


@pytest.fixture(scope="module")
def demo_run(tmp_path_factory):
    from radioslam.pipeline import evaluate_stage, simulate_and_sense, slam_stage

    out = tmp_path_factory.mktemp("demo")
    timings = simulate_and_sense("paper-cnv", out, 1, None)
    slam_stage(out, timings=timings)
    return out, evaluate_stage(out)


def test_demo_meets_its_targets_on_seed_1(demo_run):
    out, m = demo_run
    assert m["ate_rmse_m"] <= 0.10
    assert m["ate_rmse_odometry_m"] > m["ate_rmse_m"]
    assert m["loop_closures"] >= 1
    assert m["map_error_m"] <= 0.25
    assert m["map_coverage"] >= 0.7
    assert m["poses"] == 60
    assert json.loads((out / "metrics.json").read_text()) == m


def test_run_directory_files_are_complete_and_consistent(demo_run):
    out, _ = demo_run
    t, est = read_tum(out / "trajectory.tum")
    _, odo = read_tum(out / "trajectory_odometry.tum")
    assert len(t) == len(est) == len(odo) == 60
    assert np.allclose(est[0], 0) and np.allclose(odo[0], 0)  # the first scan defines the map frame
    cells, meta = read_ros_map(out / "map.yaml")
    assert (cells == OCCUPIED).sum() > 100 and (cells == FREE).sum() > 1000
    from radioslam.io.ply import read_map_points

    assert len(read_map_points(out / "map.ply")) == pytest.approx(60 * 36, rel=0.2)
    assert not list(out.glob(".*.tmp"))  # no half-written file left behind
