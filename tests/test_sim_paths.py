"""Echo paths: delays against 2R/c + T_H, gains against the model of sim.paths."""

import numpy as np
import pytest

from radioslam.antenna import BeamSet
from radioslam.config import SPEED_OF_LIGHT
from radioslam.scene import builtin_scene, scene_from_mapping
from radioslam.sim import PathKind, echo_paths, strongest_echo


@pytest.mark.parametrize("r", [0.8, 3.2, 6.4, 12.8])
def test_single_plate_strongest_echo_is_2r_over_c_plus_hardware_delay(r):
    scene = builtin_scene(f"single-plate:{r}")
    radio = scene.radio
    paths = echo_paths(scene, scene.poses[0])
    beams = BeamSet.from_config(radio)
    boresight = np.flatnonzero((beams.orientation == 0) & (beams.index == 0))[0]
    k = strongest_echo(beams, paths, boresight)
    total = paths.delay_s[k] + radio.hardware_delay_s
    b = radio.array_baseline_m
    assert total == pytest.approx(2 * np.sqrt(r**2 + b**2 / 4) / SPEED_OF_LIGHT + radio.hardware_delay_s,
                                  abs=1e-15)
    # the TX/RX offset adds b²/(4r) of path: under 1 mm here
    assert abs(total - (2 * r / SPEED_OF_LIGHT + radio.hardware_delay_s)) < 2e-3 / SPEED_OF_LIGHT
    assert paths.kind[k] == PathKind.SPECULAR
    assert np.allclose(paths.point[k], [r, 0.0])


def test_specular_amplitude_follows_the_image_source_model(radio):
    scene = builtin_scene("single-plate:4")
    paths = echo_paths(scene, scene.poses[0])
    k = np.flatnonzero(paths.kind == PathKind.SPECULAR)[0]
    metal = scene.materials[scene.material_names.index("metal")]
    expected = radio.wavelength_m / (4 * np.pi * 8.0) * metal.reflectivity * np.sqrt(1 - metal.scattering**2)
    assert abs(paths.amplitude[k]) == pytest.approx(expected, rel=1e-4)
    # carrier phase of the round trip
    assert np.angle(paths.amplitude[k]) == pytest.approx(
        np.angle(np.exp(-2j * np.pi * radio.carrier_hz * paths.delay_s[k])), abs=1e-6)


def test_diffuse_power_is_independent_of_ray_density():
    base = builtin_scene("single-plate:4")
    powers = []
    for spacing in (0.05, 0.1, 0.2):
        scene = base.with_radio(ray_spacing_deg=spacing)
        paths = echo_paths(scene, scene.poses[0], leakage=False)
        diffuse = paths.kind == PathKind.DIFFUSE
        powers.append(np.sum(np.abs(paths.amplitude[diffuse]) ** 2))
    assert np.ptp(powers) / np.mean(powers) < 0.02


def test_leakage_is_set_by_isolation_and_arrives_first():
    scene = builtin_scene("single-plate:4").with_radio(isolation_db=50.0)
    paths = echo_paths(scene, scene.poses[0])
    leak = paths.kind == PathKind.LEAKAGE
    assert leak.sum() == 1
    assert abs(paths.amplitude[leak][0]) == pytest.approx(10 ** (-50 / 20))
    assert paths.delay_s[leak][0] == pytest.approx(scene.radio.array_baseline_m / SPEED_OF_LIGHT)
    assert paths.delay_s[leak][0] < paths.delay_s[~leak].min()


def test_glass_door_sees_the_door_and_the_wall_behind_it():
    scene = builtin_scene("glass-door")
    paths = echo_paths(scene, scene.poses[0], leakage=False)
    ahead = np.abs(paths.angle) < np.radians(3)
    walls = {scene.spec.walls[w].material for w in scene.segment_wall[paths.segment[ahead]]}
    assert walls == {"glass", "concrete"}
    assert (ahead & np.isclose(paths.point[:, 0], 15.0)).any()


def test_wall_behind_glass_is_attenuated_by_two_way_transmission():
    door = builtin_scene("glass-door")
    spec = door.spec.model_dump()
    spec["walls"] = spec["walls"][1:]  # the same room without the door leaf
    open_room = scene_from_mapping(spec)
    with_leaf = echo_paths(door, door.poses[0], leakage=False)
    without = echo_paths(open_room, open_room.poses[0], leakage=False)

    def far_diffuse(p):
        keep = (p.kind == PathKind.DIFFUSE) & np.isclose(p.point[:, 0], 15.0) & (np.abs(p.angle) < 0.05)
        return dict(zip(np.round(p.angle[keep], 9), p.amplitude[keep]))

    a, b = far_diffuse(with_leaf), far_diffuse(without)
    behind_leaf = [k for k in a if abs(np.tan(k) * 4.96) < 0.3]  # rays through the leaf near y = 0
    assert behind_leaf
    ratio = np.array([abs(a[k] / b[k]) for k in behind_leaf])
    assert np.allclose(ratio, 0.70**2, rtol=1e-9)


def test_occluded_specular_is_dropped():
    scene = scene_from_mapping({
        "version": 1, "name": "occluded",
        "walls": [{"points": [[3, -1], [3, 1]], "material": "metal"},
                  {"points": [[6, -5], [6, 5]], "material": "concrete"}],
        "trajectory": {"poses": [[0, 0, 0]]}})
    paths = echo_paths(scene, scene.poses[0], leakage=False)
    spec = paths.kind == PathKind.SPECULAR
    assert np.allclose(paths.point[spec], [[3.0, 0.0]])


@pytest.mark.parametrize("heading_deg, world_deg", [(0, 30), (90, 120), (90, 270), (-45, 100), (10, -75)])
def test_strongest_beam_points_at_the_target_in_the_terminal_frame(heading_deg, world_deg):
    from radioslam.capture import CaptureMode
    from radioslam.sim import Simulator

    heading, direction = np.radians(heading_deg), np.radians(world_deg)
    centre = 5.0 * np.array([np.cos(direction), np.sin(direction)])
    along = 0.5 * np.array([-np.sin(direction), np.cos(direction)])
    scene = scene_from_mapping({
        "version": 1, "name": "rotated-plate",
        "walls": [{"points": [(centre - along).tolist(), (centre + along).tolist()], "material": "metal"}],
        "trajectory": {"poses": [[0.0, 0.0, float(heading)]]},
        "radio": {"snr_db": 300.0, "isolation_db": 300.0}})
    cap = Simulator.from_scene(scene, CaptureMode.GRID).simulate_pose(0, np.random.default_rng(0))
    energy = np.mean(np.abs(cap.grid) ** 2, axis=(1, 2))
    best = np.argmax(energy)
    local = np.angle(np.exp(1j * (direction - heading)))
    assert abs(np.angle(np.exp(1j * (cap.beam_angle_rad[best] - local)))) < np.radians(1.5)
