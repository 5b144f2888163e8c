"""The TX→RX leakage (issue #13, point 2): its per-beam coupling, its calibration, its cancellation with a
drift since calibration, and what that opens up: targets from 0.5 m, a 2.4 m corridor."""

import json

import numpy as np
import pytest

from radioslam.antenna.codebook import BeamSet
from radioslam.config import SPEED_OF_LIGHT, Impairments, RadioConfig
from radioslam.io import read_calibration, write_calibration
from radioslam.io.errors import CalibrationFileError
from radioslam.pipeline import calibrated_receiver, simulated_calibration
from radioslam.scene import load_scene
from radioslam.scene.geometry import point_segment_distance
from radioslam.sensing import Receiver, SensingConfig
from radioslam.sensing.calibration import measure_leakage
from radioslam.sim import Simulator
from radioslam.sim.calibration_targets import simulate_empty_capture
from radioslam.sim.paths import leakage_paths
from radioslam.slam.se2 import transform_points

DRIFT = Impairments(leakage_drift_db=1.0, leakage_drift_deg=20.0)


def test_the_arrays_couple_most_at_broadside_and_far_apart_as_the_array_factor_squared():
    beams = BeamSet.from_config(RadioConfig())
    coupling = beams.coupling()
    assert np.isclose(np.mean(np.abs(coupling) ** 2), 1.0)
    first = np.abs(coupling[:beams.per_orientation])
    assert np.allclose(first, first[::-1])  # mirror beams couple alike
    assert 20 * np.log10(first[beams.beams_per_side] / first[0]) > 10.0
    # arrays far apart see each other as one point: C → c·11ᵀ, so |L_i| ∝ |w_iᴴ·1|², the one-way
    # array factor at broadside, squared
    far = BeamSet(8, 6, 23, 1, element_exponent=0.0, baseline_wavelengths=1e4)
    gain = far.two_way_gain(np.array([0.0]))[:, 0]
    assert np.allclose(np.abs(far.coupling()), gain / np.sqrt(np.mean(gain**2)), atol=1e-3)
    assert np.allclose(BeamSet.from_config(RadioConfig(leakage_coupling="uniform")).coupling(), 1.0)


def test_an_empty_sweep_measures_every_beams_leakage_delay_and_amplitude():
    radio = RadioConfig(leakage_excess_delay_s=0.4e-9, impairments=DRIFT)
    model = measure_leakage(simulate_empty_capture(radio, np.random.default_rng(3)))
    truth_s = radio.hardware_delay_s + radio.array_baseline_m / SPEED_OF_LIGHT + radio.leakage_excess_delay_s
    error = (model.delay_s - truth_s) * radio.sample_rate_hz
    assert np.median(np.abs(error)) < 0.01 and np.abs(error).max() < 0.05  # samples
    # as calibrated: before the drift
    truth = 10 ** (-radio.isolation_db / 20) * BeamSet.from_config(radio).coupling()
    assert np.median(np.abs(model.amplitude / truth - 1)) < 0.02


def test_cancelling_the_leakage_at_a_wrong_lag_leaves_ghosts_near_it_and_at_the_calibrated_lag_none():
    """With the coupling path 4 ns longer than b/c (1.2 m of cable or board) and the leakage drifted by
    1 dB and 20° since calibration, a sweep with nothing in range must give no point from 0.5 m on; a
    receiver that assumes b/c reads the residual as targets, even behind the old 1.5 m gate."""
    radio = RadioConfig(leakage_excess_delay_s=4e-9, impairments=DRIFT)
    nothing = Simulator.from_radio(radio).capture_from_paths(leakage_paths(radio), np.random.default_rng(4))
    receiver = calibrated_receiver(radio, seed=5)
    assert receiver.min_range_m <= 0.8
    assert len(receiver.sense(nothing).scan.range_m) == 0
    for gate in (receiver.min_range_m, 1.5):
        assumed = Receiver(radio, receiver.hardware_delay_s, SensingConfig(min_range_m=gate))
        assert len(assumed.sense(nothing).scan.range_m) > 20


@pytest.mark.parametrize("range_m", [0.6, 0.8, 1.0, 1.2, 1.5])
def test_plates_from_0_6_m_are_ranged_within_5_cm_while_the_leakage_drifts(range_m):
    radio = RadioConfig(impairments=DRIFT)
    receiver = calibrated_receiver(radio, seed=1)
    scene = load_scene(f"single-plate:{range_m}").with_radio(impairments=DRIFT)
    capture = Simulator.from_scene(scene, rows=[radio.beams_per_side]).simulate_pose(0, np.random.default_rng(2))
    result = receiver.sense(capture)
    assert result.valid[0, 0]
    assert abs(result.range_m[0, 0] - range_m) < 0.05


def test_calibration_json_round_trips_the_leakage_and_names_a_bad_field(tmp_path):
    cal = simulated_calibration(RadioConfig(beams_per_side=3, orientations=1), seed=0, targets=3)
    path = tmp_path / "calibration.json"
    write_calibration(path, cal)
    back = read_calibration(path)
    assert back.hardware_delay_s == cal.hardware_delay_s
    assert np.array_equal(back.leakage.delay_s, cal.leakage.delay_s)
    assert np.array_equal(back.leakage.amplitude, cal.leakage.amplitude)
    assert np.array_equal(back.leakage.beam_index, np.arange(-3, 4))
    doc = json.loads(path.read_text())
    doc["leakage"]["delay_s"][2] = "soon"
    path.write_text(json.dumps(doc))
    with pytest.raises(CalibrationFileError) as err:
        read_calibration(path)
    assert err.value.field == "leakage.delay_s"
    # the beams' keys are whole numbers, each beam listed once: no silent truncation to another beam
    good = json.dumps({**doc, "leakage": {**doc["leakage"], "delay_s": cal.leakage.delay_s.tolist()}})
    for field, value, why in [("orientation", 0.5, "whole numbers"), ("beam_index", -2.7, "whole numbers"),
                              ("orientation", -1, "whole numbers ≥ 0"), ("beam_index", -3, "listed twice")]:
        doc = json.loads(good)
        doc["leakage"][field][1] = value
        path.write_text(json.dumps(doc))
        with pytest.raises(CalibrationFileError) as err:
            read_calibration(path)
        assert why in str(err.value)


def test_a_receiver_asked_for_a_beam_its_leakage_calibration_lacks_says_which():
    from radioslam.sensing import SensingError

    radio = RadioConfig(beams_per_side=3, orientations=1)
    receiver = calibrated_receiver(radio, seed=0)
    wider = RadioConfig(beams_per_side=5, orientations=1)
    capture = simulate_empty_capture(wider, np.random.default_rng(0))
    with pytest.raises(SensingError, match="index -5"):
        receiver.sense(capture)


def test_a_corridor_2_4_m_wide_is_seen_wall_by_wall_once_the_leakage_is_calibrated():
    """Walked along its middle, every side wall 1.2 m away: with the gate at 1.5 m (leakage not
    calibrated) those walls are invisible and their echoes' skirts beyond it are read as far arcs."""
    scene = load_scene("narrow-corridor")
    simulator = Simulator.from_scene(scene)
    near, far = calibrated_receiver(scene.radio, seed=1), Receiver(scene.radio, scene.radio.hardware_delay_s)
    off = {"near": [], "far": []}
    for pose in range(0, 30, 3):
        capture = simulator.simulate_pose(pose, np.random.default_rng(pose))
        for name, receiver in (("near", near), ("far", far)):
            scan = receiver.sense(capture).scan
            world = transform_points(scene.poses[pose], scan.xy)
            off[name].append(point_segment_distance(world, scene.segments).min(axis=1))
    near_off, far_off = np.concatenate(off["near"]), np.concatenate(off["far"])
    assert len(near_off) > 200 and near_off.max() < 0.3
    assert np.mean(far_off > 0.3) > 0.2
