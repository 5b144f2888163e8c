"""The motion prior and the measurement model (issue #47): probabilities with a meaning, not discounts."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from radioslam.slam.motion_prior import PLATFORMS, MotionPrior, Platform

UNKNOWN = PLATFORMS[Platform.UNKNOWN]


def _grid_mass(prior: MotionPrior, half_m: float, n: int = 52, turns: int = 72) -> float:
    """∫ p(s) ds over ±half_m × ±half_m × (−π, π] on a midpoint grid."""
    dx = 2 * half_m / n
    x = -half_m + (np.arange(n) + 0.5) * dx
    t = -np.pi + (np.arange(turns) + 0.5) * 2 * np.pi / turns
    grid = np.stack(np.meshgrid(x, x, t, indexing="ij"), axis=-1).reshape(-1, 3)
    return float(np.exp(prior.log_prob(grid)).sum() * dx * dx * 2 * np.pi / turns)


@pytest.mark.parametrize("platform", list(Platform))
def test_the_step_density_integrates_to_one(platform):
    """A density over steps: the Gaussians' mass (ℝ², a few σ) and the unexpected's (the searched window,
    ±max_step_m) sum to 1; over the window alone, all but the Gaussians' tails beyond it."""
    steps = np.array([[0.5, 0.0, 0.1], [0.0, 0.0, 0.0]])
    prior = MotionPrior.of(steps, PLATFORMS[platform], max_step_m=1.3)
    assert _grid_mass(prior, 3.5, n=140) == pytest.approx(1.0, abs=0.02)
    assert 0.9 < _grid_mass(prior, 1.3) <= 1.0


def test_a_half_turn_is_possible_but_never_free():
    """The heavy tail: a half turn costs at least log((1 − ε) N_peak / (ε U)) against the expected step,
    and is finite; the same turn measured by odometry costs nothing."""
    walking = np.array([[0.5, 0.0, 0.0]])
    prior = MotionPrior.of(walking, UNKNOWN, max_step_m=1.3)
    expected, half_turn = prior.log_prob(np.array([[0.5, 0.0, 0.0], [-0.5, 0.0, np.pi]]))
    uniform = np.log(UNKNOWN.surprise) - np.log(2.6**2 * 2 * np.pi)
    assert np.isfinite(half_turn) and half_turn >= uniform  # the tail bounds it from below
    assert expected - half_turn > 5.0  # e^5 ≈ 150 : 1 against, before any scan evidence
    odometry = MotionPrior.of(np.array([[-0.5, 0.0, np.pi]]), UNKNOWN, 1.3, np.array([0.02, 0.02, 0.01]))
    assert odometry.log_prob(np.array([[-0.5, 0.0, np.pi]]))[0] - odometry.log_prob(walking)[0] > 15


def test_odometry_narrows_the_prior_and_a_gyro_fixes_only_the_turn():
    """With odometry (2 cm, 0.5°) a step 10 cm off costs ≈ ½(10/2)² = 12.5 nats; a gyro's prior keeps the
    platform's translation width (a 10 cm slip is cheap) but prices a 10° turn error at ½(10/0.5)² = 200."""
    step = np.array([[0.5, 0.0, 0.0]])
    sigmas = np.array([0.02, 0.02, np.radians(0.5)])
    odometry = MotionPrior.of(step, UNKNOWN, 1.3, sigmas)
    at, off = odometry.log_prob(np.array([[0.5, 0.0, 0.0], [0.6, 0.0, 0.0]]))
    assert at - off == pytest.approx(12.5, rel=1e-3)
    gyro = MotionPrior.of(step, UNKNOWN, 1.3, gyro=(0.0, np.radians(0.5)))
    at, slip, turned = gyro.log_prob(np.array([[0.5, 0.0, 0.0], [0.6, 0.0, 0.0], [0.5, 0.0, np.radians(10)]]))
    assert at - slip == pytest.approx(0.5 * (0.1 / UNKNOWN.along_m) ** 2, rel=1e-3)
    assert at - turned > 10  # bounded by the tail, far beyond any scan's odds


@settings(max_examples=50, deadline=None)
@given(st.floats(-np.pi, np.pi), st.floats(-1.0, 1.0), st.floats(-1.0, 1.0))
def test_the_prior_is_continuous_and_periodic_in_the_turn(turn, x, y):
    """log p is periodic in θ (a step turned by 2π is the same step) and moves little for a nanometre."""
    prior = MotionPrior.of(np.array([[0.4, 0.1, 0.3], [0.0, 0.0, 0.0]]), UNKNOWN, 1.3)
    a, b, c = prior.log_prob(np.array([[x, y, turn], [x, y, turn + 2 * np.pi], [x + 1e-9, y, turn]]))
    assert a == pytest.approx(b, abs=1e-9) and a == pytest.approx(c, abs=1e-6)


def test_the_measurement_model_counts_an_arc_once():
    """A scan's log-likelihood weighs each point by 1/n of its arc's n points: an arc of ten beams seeing
    one wall is one echo, worth as much as one point alone; space the map saw through costs twice the
    floor."""
    from radioslam.sensing.pointcloud import Scan
    from radioslam.slam.measurement import LOG_FLOOR, point_log_likelihoods
    from radioslam.slam.normals import echo_weights

    beams = np.concatenate([np.arange(10, 20), [30]])
    scan = Scan(range_m=np.r_[np.full(10, 3.0), 5.0], angle_rad=np.radians(beams.astype(float)),
                power_db=np.zeros(11), beam=beams, orientation=np.zeros(11, int))
    weights = echo_weights(scan, arc_range_m=0.1)
    assert weights[:10] == pytest.approx(0.1) and weights[10] == 1.0 and weights.sum() == pytest.approx(2.0)
    assert point_log_likelihoods(np.array([1.0, 0.0, -1.0])) == pytest.approx([0.0, LOG_FLOOR, 2 * LOG_FLOOR])


def test_an_imu_rate_file_integrates_to_the_scans_headings(tmp_path):
    """``timestamp,wz`` at 100 Hz of a terminal turning 0.2 rad/s, then −0.1: the headings at the scans'
    timestamps (1 s apart) are the integral, exactly for piecewise-constant rates at the samples; x and y
    are unknown (NaN)."""
    from radioslam.pipeline.slam import read_odometry

    t = np.arange(0, 5.001, 0.01)
    rate = np.where(t < 2.0, 0.2, -0.1)
    (tmp_path / "imu.csv").write_text("timestamp,wz\n" + "\n".join(f"{a:.2f},{b}" for a, b in zip(t, rate)))
    odometry = read_odometry(tmp_path / "imu.csv", 6)
    assert np.isnan(odometry[:, :2]).all()
    assert odometry[:, 2] == pytest.approx([0.0, 0.2, 0.4, 0.3, 0.2, 0.1], abs=2e-3)  # the 2 s step: one sample


def test_a_gyro_tum_file_has_unknown_translation_on_every_line_or_none(tmp_path):
    from radioslam.io.errors import TumError
    from radioslam.io.tum import read_tum

    line = "{t} {x} {y} 0 0 0 0.0998 0.9950\n"
    (tmp_path / "gyro.tum").write_text("".join(line.format(t=t, x="nan", y="nan") for t in range(3)))
    _, poses = read_tum(tmp_path / "gyro.tum", unknown_translation=True)
    assert np.isnan(poses[:, :2]).all() and poses[:, 2] == pytest.approx(0.2, abs=1e-3)
    with pytest.raises(TumError, match="NaN"):  # a trajectory (evo's, ours) never has nan
        read_tum(tmp_path / "gyro.tum")
    (tmp_path / "mixed.tum").write_text(line.format(t=0, x="nan", y="nan") + line.format(t=1, x=1, y=2))
    with pytest.raises(TumError, match="every line"):
        read_tum(tmp_path / "mixed.tum", unknown_translation=True)


def test_a_simulated_gyro_measures_the_turns_only():
    """Scene ``odometry: {gyro_only: true}``: the headings drift as the spec says, x and y are nan."""
    from radioslam.scene.schema import OdometrySpec
    from radioslam.sim.odometry import odometry_rng, simulated_odometry

    truth = np.column_stack([np.arange(20) * 0.5, np.zeros(20), np.linspace(0, 1, 20)])
    spec = OdometrySpec(sigma_deg=0.0, heading_bias_deg=0.1, gyro_only=True)
    gyro = simulated_odometry(truth, spec, odometry_rng(3))
    assert np.isnan(gyro[:, :2]).all()
    assert gyro[:, 2] - truth[:, 2] == pytest.approx(np.radians(0.1) * np.arange(20), abs=1e-9)


def test_a_scans_clear_line_across_a_mapped_wall_costs_one_observation():
    """A specular echo at 3 m straight ahead says the 3 m in between are clear: against a map of that wall
    alone the line costs nothing; a mapped wall across it at 1.5 m costs the floor (one observation, however
    many samples cross it); turned away from that wall the line is clear again. The scan's log-likelihood is
    the points' and the lines' terms at the calibrated scale."""
    from radioslam.slam.grid import LikelihoodGrid
    from radioslam.slam.measurement import (
        LOG_FLOOR,
        TEMPERATURE,
        line_log_likelihoods,
        point_terms,
        scan_log_likelihoods,
    )

    y = np.linspace(-2.0, 2.0, 81)
    far = np.stack([np.full_like(y, 3.0), y], axis=1)
    near = np.stack([np.full_like(y, 1.5), y], axis=1)
    sighting = np.array([[0.0, 3.0]])  # bearing 0, range 3 m
    poses = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, np.pi / 2]])
    clear = LikelihoodGrid.from_points(far, 0.05, 0.05, 1.0, np.zeros(len(far)))
    crossed = LikelihoodGrid.from_points(np.vstack([far, near]), 0.05, 0.05, 1.0, np.zeros(2 * len(far)))
    assert line_log_likelihoods(clear, sighting, poses, stop=0.3) == pytest.approx([0.0, 0.0], abs=1e-6)
    assert line_log_likelihoods(crossed, sighting, poses, stop=0.3) == pytest.approx([LOG_FLOOR, 0.0], abs=1e-3)
    points, normals, weights = np.array([[3.0, 0.0]]), np.zeros(1), np.ones(1)
    total = scan_log_likelihoods(crossed, points, normals, weights, poses, sighting, 0.3)
    expected = TEMPERATURE * (point_terms(crossed, points, normals, weights, poses)
                              + line_log_likelihoods(crossed, sighting, poses, 0.3))
    assert total == pytest.approx(expected) and total[0] < TEMPERATURE * (LOG_FLOOR + 0.5)


def test_a_jump_beyond_a_step_is_a_kidnap_far_rarer_than_a_sudden_turn():
    """The unexpected is two events with their own shares: a slip or a sudden turn within a step's reach (ε,
    uniform over the searched window) and the terminal carried beyond it (a kidnap: ε_J, uniform over the area
    searched). Over an area as large as the window a jump is ε / ε_J times less probable than a surprise within
    it (200 : 1 for an unknown platform): a fold onto a look-alike place far away pays for its jump, where one
    share for both priced a teleport like a sudden turn. With no area given (the front end's own search) a step
    beyond the window has only the Gaussians' tails."""
    prior = MotionPrior.of(np.array([[0.5, 0.0, 0.0]]), UNKNOWN, max_step_m=1.3)
    window = (2 * 1.3) ** 2
    inside, beyond = prior.log_prob(np.array([[-1.2, 1.2, 2.0], [5.0, 5.0, 2.0]]), area_m2=window)
    assert inside - beyond == pytest.approx(np.log(UNKNOWN.surprise / UNKNOWN.jump), abs=0.01)
    assert np.log(UNKNOWN.surprise / UNKNOWN.jump) > np.log(20.0)  # beyond the ending's odds
    assert prior.log_prob(np.array([[5.0, 5.0, 2.0]]))[0] < beyond - 50.0
    assert all(0 < PLATFORMS[p].jump < PLATFORMS[p].surprise for p in PLATFORMS)
