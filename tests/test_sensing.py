"""Sensing: T1/T2 against 2R/c + T_H, bisection precision and cost, calibration (eq. 11),
the CRB, Fig. 5/8 physics, multi-target detection on glass-door, and bad input."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from radioslam.capture import CaptureMode
from radioslam.config import SPEED_OF_LIGHT, RadioConfig, bistatic_delay_s
from radioslam.eval.point_targets import capture_point_targets, nearest_beam, point_paths
from radioslam.scene import load_scene
from radioslam.scene.geometry import point_segment_distance
from radioslam.sensing import Detector, PointFilter, Receiver, SensingConfig, estimate_hardware_delay
from radioslam.sensing.bisection import bisect_peaks, iterations_for, neighbour_values
from radioslam.sensing.cfar import cfar_threshold, row_median
from radioslam.sensing.config import CfarKind
from radioslam.sensing.detect import LagGate
from radioslam.sensing.profile import RangeSpectrum, divide_by_real, signed_lag
from radioslam.sensing.sync import coarse_sync
from radioslam.sim import Simulator
from radioslam.sim.calibration_targets import calibration_ranges, simulate_calibration_captures

RADIO = RadioConfig()
FS = RADIO.sample_rate_hz


def distance_to_segments(points, seg):
    """Distance (P,) of each point to the nearest wall segment (S, 2, 2)."""
    return point_segment_distance(points, seg).min(axis=1)


def plate_capture(r, seed=0, mode=CaptureMode.WAVEFORM, **radio):
    scene = load_scene(f"single-plate:{r}").with_radio(**radio)
    return scene, Simulator.from_scene(scene, mode, rows=[RADIO.beams_per_side]).simulate_pose(
        0, np.random.default_rng(seed))


@pytest.mark.parametrize("r", [2.4, 7.2, 12.8])
def test_t1_and_t2_add_up_to_the_echo_delay(r):
    scene, cap = plate_capture(r)
    rx = Receiver(scene.radio, scene.radio.hardware_delay_s, SensingConfig(min_range_m=0.3))
    res = rx.sense(cap)
    truth = scene.radio.hardware_delay_s + bistatic_delay_s(r, scene.radio.array_baseline_m)
    # T1 alone is on the 4-sample grid, at the strongest PSS arrival: the plate, or at 12.8 m
    # the equally strong TX→RX leakage at T_H
    arrivals = np.array([truth, scene.radio.hardware_delay_s])
    assert np.min(np.abs(res.t1_s[0] - arrivals)) * FS <= 2.5
    # T1 + T2 is the echo delay 2R/c + T_H to picoseconds (millimetres of range; 3σ at 12.8 m)
    assert abs(res.delay_s[0, 0] - truth) < 2 * 6e-3 / SPEED_OF_LIGHT
    assert abs(res.range_m[0, 0] - r) < 6e-3


def test_sync_finds_thousands_of_samples_of_hardware_delay():
    _, cap = plate_capture(4.0, hardware_delay_s=50e-6)
    sync = coarse_sync(cap)
    assert sync.found.all()
    # within one step of the 4-sample sync grid of the arrivals' span (the leakage at T_H, the plate 3.3
    # samples later): the two add in the correlation's 8-sample main lobe, so its peak may sit beyond both
    assert -4 <= sync.t1_samples[0] - 50e-6 * FS <= 4 + 4.0 * 2 / SPEED_OF_LIGHT * FS


def test_grid_and_waveform_modes_give_the_same_range():
    scene, wave = plate_capture(5.6, seed=3)
    _, grid = plate_capture(5.6, seed=3, mode=CaptureMode.GRID)
    rx = Receiver(scene.radio, scene.radio.hardware_delay_s)
    assert abs(rx.sense(wave).range_m[0, 0] - rx.sense(grid).range_m[0, 0]) < 2e-3


@pytest.mark.parametrize("precision", [0.1, 0.01, 0.001])
def test_bisection_reaches_its_precision_and_counts_its_dft_evaluations(precision):
    p, n = np.arange(-396, 396), 1024
    truth = np.random.default_rng(0).uniform(2, 40, size=64)
    spec = RangeSpectrum(np.exp(-2j * np.pi * truth[:, None] * p / n), np.ones((64, len(p))), p, n)
    profile = spec.profile()
    peaks = np.argmax(np.abs(profile), axis=1)[:, None]
    steps = iterations_for(precision, 40)
    out = bisect_peaks(spec, peaks, neighbour_values(profile, peaks), steps)
    assert np.abs(out.lag[:, 0] - truth).max() <= 2.0**-steps
    assert out.dft_evaluations == steps * 64
    assert np.all(np.abs(out.amplitude) > 0.98) and np.all(np.abs(out.amplitude) < 1 + 1e-9)


def test_calibration_recovers_the_hardware_delay_within_a_nanosecond():
    radio = RADIO.model_copy(update={"hardware_delay_s": 27.3e-6})
    ranges = calibration_ranges(radio)
    cal = estimate_hardware_delay(simulate_calibration_captures(radio, ranges, seed=5), ranges)
    assert abs(cal.hardware_delay_s - 27.3e-6) < 1e-9
    assert abs(cal.hardware_delay_s - 27.3e-6) < 20e-12  # in fact to picoseconds
    assert len(cal.targets) == 16 and cal.targets[0].range_m == pytest.approx(0.8)


def test_receiver_uses_the_calibrated_delay_not_the_configured_one():
    scene, cap = plate_capture(6.4)
    off = Receiver(scene.radio, scene.radio.hardware_delay_s + 1e-9, SensingConfig(min_range_m=0.3)).sense(cap)
    assert off.range_m[0, 0] == pytest.approx(6.4 - 0.5 * SPEED_OF_LIGHT * 1e-9, abs=3e-3)


def test_empty_beams_give_no_points_and_never_range_zero():
    paths = point_paths(RADIO, 6.0, 0.0, 10.0)
    rows = list(range(188))
    cap = capture_point_targets(RADIO, paths, rows, np.random.default_rng(1))
    res = Receiver(RADIO, RADIO.hardware_delay_s).sense(cap)
    behind = np.abs(np.angle(np.exp(1j * (cap.beam_angle_rad - np.pi)))) < np.pi / 4
    assert not res.valid[behind].any()  # only noise and leakage there
    assert len(res.scan) > 0 and (res.scan.range_m >= 1.5).all()
    assert np.all(np.abs(res.scan.range_m - 6.0) < 0.05)


def test_cfar_false_alarm_rate_matches_its_design():
    rng = np.random.default_rng(0)
    noise = rng.exponential(size=(400, 1024))
    for kind in CfarKind:
        rate = np.mean(noise > cfar_threshold(noise, kind, 2, 16, 1e-3))
        assert 0.5e-3 < rate < 2e-3, (kind, rate)


@given(st.integers(1, 300), st.integers(1, 4), st.integers(0, 2**32 - 1))
@settings(max_examples=40, deadline=None)
def test_the_noise_floors_median_is_numpys(n, rows, seed):
    values = np.random.default_rng(seed).exponential(size=(rows, n))
    values[:, ::3] = values[:, :1]  # ties
    assert np.array_equal(row_median(values), np.median(values, axis=-1))


def test_dividing_by_a_real_divisor_in_place_divides_each_part():
    rng = np.random.default_rng(3)
    values = rng.standard_normal((5, 64)) + 1j * rng.standard_normal((5, 64))
    divisor = rng.uniform(0.1, 10.0, 5)
    complex_division = values / divisor[:, None]
    parts = values.real / divisor[:, None], values.imag / divisor[:, None]
    divide_by_real(values, divisor)
    assert np.array_equal(values.real, parts[0]) and np.array_equal(values.imag, parts[1])
    np.testing.assert_array_max_ulp(values.real, complex_division.real, maxulp=1)
    np.testing.assert_array_max_ulp(values.imag, complex_division.imag, maxulp=1)


@pytest.mark.parametrize("low, high", [((30.2, 34.6, 26.0), (62.9, 66.95, 58.0)),  # the range gate
                                       ((-5.5, -3.0, 2.0), (4.0, 9.5, 7.0)),  # around lag 0: wraps
                                       ((-512.0, -511.5, -600.0), (512.0, 512.5, 600.0))])  # wider than N
def test_the_gates_window_holds_the_same_local_maxima_as_the_whole_profile(low, high):
    n = 1024
    power = np.random.default_rng(5).exponential(size=(3, n))
    gate = LagGate(np.array(low), np.array(high), np.full(3, np.nan))
    floor = np.full((3, 1), 1.5)
    whole = ((power > np.roll(power, 1, axis=1)) & (power >= np.roll(power, -1, axis=1))
             & gate.contains(signed_lag(np.arange(n), n)[None, :]) & (power > floor))
    window = gate.window(n)
    found, gated_power = window.maxima(power, floor)
    rows, cells = np.nonzero(found)
    assert len(set(window.inner)) == len(window.inner)  # each column once
    assert sorted(zip(rows, window.inner[cells])) == sorted(zip(*np.nonzero(whole)))
    assert np.array_equal(gated_power[rows, cells], power[rows, window.inner[cells]])


def test_multi_target_mode_finds_the_glass_door_and_the_wall_behind_it():
    scene = load_scene("glass-door")
    cap = Simulator.from_scene(scene).simulate_pose(0, np.random.default_rng(0))
    scan = Receiver(scene.radio, scene.radio.hardware_delay_s, SensingConfig(detector=Detector.MULTI)).sense(cap).scan
    xy = scan.xy
    ahead = np.abs(scan.angle_rad) < np.radians(20)
    door, wall = ahead & (xy[:, 0] < 8), ahead & (xy[:, 0] > 12)
    assert door.sum() >= 5 and wall.sum() >= 5
    distance_to_walls = lambda points: distance_to_segments(points, scene.segments)  # noqa: E731
    assert distance_to_walls(xy[door | wall]).max() < 0.3
    # one target per beam: with the paper's rule the wall behind the door is lost; with the same-range
    # rule a beam or two may see it, and then on the wall
    paper = SensingConfig(point_filter=PointFilter.SCAN_PEAK)
    single = Receiver(scene.radio, scene.radio.hardware_delay_s, paper).sense(cap).scan
    assert not ((np.abs(single.angle_rad) < np.radians(20)) & (single.xy[:, 0] > 12)).any()
    single = Receiver(scene.radio, scene.radio.hardware_delay_s).sense(cap).scan
    behind = (np.abs(single.angle_rad) < np.radians(20)) & (single.xy[:, 0] > 12)
    assert behind.sum() < wall.sum() and (distance_to_walls(single.xy[behind]) < 0.3).all()


def test_fig8_matched_filter_resolves_the_weak_target_the_pdp_misses():
    from radioslam.eval.experiments.fig8 import run_fig8

    r = run_fig8(trials=20, seed=4)
    assert r.detect_rate_mf >= 0.95 and r.detect_rate_pdp < r.detect_rate_mf


def test_fig5_different_data_lowers_sidelobes_identical_does_not():
    from radioslam.eval.experiments.fig5 import run_fig5

    r = run_fig5(snr_db=(10.0, 20.0), trials=8, seed=1)
    assert r.peak_sidelobe_db["different"][0] <= r.peak_sidelobe_db["single"][0] - 4
    assert r.peak_sidelobe_db["single"][1] - r.peak_sidelobe_db["identical"][1] <= 1.5


def test_nearest_beam_points_at_the_bearing():
    assert np.degrees(Simulator.from_radio(RADIO).beams.angle[nearest_beam(RADIO, np.pi / 4)]) == pytest.approx(
        45, abs=1.0)


def test_refining_only_contender_peaks_gives_the_same_scan(monkeypatch):
    """Single mode skips peaks > 6 dB below the strongest: same detections, fewer DFT evaluations."""
    from radioslam.sensing import detect

    scene = load_scene("paper-cnv")
    cap = Simulator.from_scene(scene).simulate_pose(7, np.random.default_rng(1))
    rx = Receiver(scene.radio, scene.radio.hardware_delay_s)
    pruned = rx.sense(cap)
    monkeypatch.setattr(detect, "CONTENDER_DB", None)
    full = rx.sense(cap)
    assert np.array_equal(pruned.valid, full.valid)
    assert np.allclose(pruned.range_m[pruned.valid], full.range_m[full.valid], rtol=0, atol=1e-9)
    assert pruned.dft_evaluations < full.dft_evaluations


def test_same_range_rule_drops_sidelobes_at_an_echos_range_and_keeps_far_weak_walls():
    from radioslam.sensing.pointcloud import build_scan

    # beams: a near wall (0 dB), a beam sidelobe of it at its range (−15 dB), the same range at −12 dB,
    # a far wall at −18 dB, a far echo below the −25 dB floor, and an empty beam
    rng = np.array([[2.0], [2.3], [1.5], [9.0], [12.0], [np.nan]])
    rel = np.array([0.0, -15.0, -12.0, -18.0, -28.0, 0.0])
    valid = np.isfinite(rng)
    power = np.where(valid[:, 0], 10 ** (rel / 10), 0.0)[:, None] * 4.0
    args = (rng, power, valid, np.arange(6) * 0.1, np.arange(6), np.zeros(6), -13.0)
    same = build_scan(*args, floor_db=-25.0, cell_m=SPEED_OF_LIGHT / (2 * FS))
    assert sorted(same.range_m) == [1.5, 2.0, 9.0]
    assert same.power_db == pytest.approx([0.0, -12.0, -18.0])
    assert sorted(build_scan(*args).range_m) == [1.5, 2.0]  # the paper's rule: within 13 dB of the scan's peak


def test_a_corridors_far_end_wall_becomes_points_and_its_sidelobes_do_not():
    from radioslam.scene.loader import scene_from_mapping

    wall = lambda pts: {"points": pts, "material": "concrete"}  # noqa: E731
    scene = scene_from_mapping({"version": 1, "name": "corridor", "walls": [
        wall([[-20.0, -2.0], [9.0, -2.0], [9.0, 2.0], [-20.0, 2.0]])],
        "trajectory": {"poses": [[0.0, 0.0, 0.0]]}}, "test:corridor")
    cap = Simulator.from_scene(scene).simulate_pose(0, np.random.default_rng(3))
    delay = scene.radio.hardware_delay_s
    same = Receiver(scene.radio, delay).sense(cap).scan
    paper = Receiver(scene.radio, delay, SensingConfig(point_filter=PointFilter.SCAN_PEAK)).sense(cap).scan
    end = lambda s: (np.abs(s.angle_rad) < np.radians(10)) & (np.abs(s.range_m - 9.0) < 0.1)  # noqa: E731
    assert end(same).sum() >= 2 and not end(paper).any()  # 20·log10(9/2) = 13.1 dB below the side walls
    assert -25.0 <= same.power_db[end(same)].max() < -13.0
    # the side walls' arcs are the paper's: their beam sidelobes (a global −25 dB threshold takes
    # 40–130° of arc) stay out, and every point lies on a wall
    side = lambda s: np.sort(s.angle_rad[s.range_m < 2.5])  # noqa: E731
    assert np.array_equal(side(same), side(paper)) and len(side(paper)) >= 10
    wide = SensingConfig(point_filter=PointFilter.SCAN_PEAK, point_threshold_db=-25.0)
    assert len(side(Receiver(scene.radio, delay, wide).sense(cap).scan)) > 2 * len(side(paper))
    assert distance_to_segments(same.xy, scene.segments).max() < 0.3
