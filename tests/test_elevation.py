"""Elevation beams and 3D point clouds (issue #16): the UPA's separable codebook against its array factor,
the 2.5D caster's calibration and geometry, heights estimated between the rows, z through the files."""

import numpy as np
import pytest

from radioslam.antenna.codebook import BeamSet
from radioslam.config import RadioConfig
from radioslam.eval.map3d import height_error_summary, match_surfaces
from radioslam.io.ply import read_map_points, read_scan, write_scan
from radioslam.scene import scene_from_mapping
from radioslam.scene.mesh import Mesh
from radioslam.sensing import Receiver
from radioslam.sensing.leakage import LeakageModel
from radioslam.sensing.pointcloud import Scan
from radioslam.sim import beam_path_gains, echo_paths
from radioslam.sim.elevated import CEILING_SEGMENT, FLOOR_SEGMENT, bistatic_slant_delay
from radioslam.sim.noise import noise_variance
from radioslam.sim.paths import EchoPaths, PathKind
from radioslam.sim.simulator import Simulator

C = 299_792_458.0
BOX = {"version": 1, "name": "box", "walls": [{"points": [[-4, -3], [5, -3], [5, 3], [-4, 3], [-4, -3]],
                                               "material": "concrete"}],
       "trajectory": {"poses": [[0.0, 0.0, 0.3]]}}


def test_upa_beams_against_the_array_factor():
    """Beam (i, j) of the 8×8 array: |Σ_n e^{jπn(u_y − 2i/64)}|²/8 · |Σ_r e^{jπr(u_z − 2j/64)}|²/64 · cos ψ
    towards (φ, ε) (the element pattern cos^q, q = 1), and the beam whose (u_y, u_z) is nearest wins."""
    beams = BeamSet.from_config(RadioConfig(elevation_beams=5))
    assert len(beams) == 4 * 47 * 5 and set(beams.elevation_index) == {-8, -4, 0, 4, 8}
    phi, eps = np.radians([10.0, -30.0, 3.0]), np.radians([12.0, -5.0, 0.0])
    gain = beams.two_way_gain(phi, eps)
    local = np.angle(np.exp(1j * (phi[None, :] - beams.orientation[:, None] * np.pi / 2)))  # (B, P)
    u_y, u_z = np.cos(eps) * np.sin(local), np.sin(eps)
    n = np.arange(8)[None, :, None]
    horizontal = np.abs(np.exp(1j * np.pi * n * (u_y[:, None, :] - 2 * beams.index[:, None, None] / 64)).sum(axis=1))
    vertical = np.abs(np.exp(1j * np.pi * n * (u_z - 2 * beams.elevation_index[:, None, None] / 64)).sum(axis=1))
    expected = horizontal**2 / 8 * vertical**2 / 64 * np.clip(np.cos(eps) * np.cos(local), 0, None)
    expected[np.abs(local) >= np.pi / 2] = 0.0  # behind the array
    np.testing.assert_allclose(gain, expected, rtol=1e-9, atol=1e-12)
    best = np.argmax(gain, axis=0)
    assert np.all(np.abs(np.sin(beams.elevation[best]) - u_z) <= 2 * 4 / 64 / 2 + 1e-12)


def test_flat_rows_are_the_flat_scan():
    """The horizontal row of an elevation sweep is the flat scan's beams, gains and angles exactly."""
    flat, raised = BeamSet.from_config(RadioConfig()), BeamSet.from_config(RadioConfig(elevation_beams=3))
    rows = raised.elevation_index == 0
    theta = np.radians(np.linspace(-179, 179, 41))
    np.testing.assert_array_equal(raised.angle[rows], flat.angle)
    np.testing.assert_allclose(raised.two_way_gain(theta)[rows], flat.two_way_gain(theta), rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(raised.two_way_gain(theta, np.zeros_like(theta))[rows], flat.two_way_gain(theta),
                               rtol=1e-12, atol=1e-15)


def test_fan_keeps_the_flat_casters_calibration_and_geometry():
    """An unbounded wall returns on the horizontal row the power the 2D caster gives (the fan's normalization
    W), within 1.5 dB (the slant ranges and the coarser fan); every echo's delay is the TX→point→RX path;
    an extruded floor's and ceiling's echoes lie on them (height ± Δz from the slant range and elevation)."""
    flat = scene_from_mapping({**BOX, "radio": {"isolation_db": 400}})
    raised = scene_from_mapping({**BOX, "radio": {"isolation_db": 400, "elevation_beams": 3}})
    pose = flat.poses[0]
    flat_paths, fan_paths = echo_paths(flat, pose), echo_paths(raised, pose)
    flat_power = np.sum(np.abs(beam_path_gains(BeamSet.from_config(flat.radio), flat_paths)) ** 2, axis=1)
    beams = BeamSet.from_config(raised.radio)
    diffuse = fan_paths.kind == PathKind.DIFFUSE
    fan_gain = beam_path_gains(beams, fan_paths)
    specular = np.abs(beam_path_gains(BeamSet.from_config(flat.radio), flat_paths)[:, flat_paths.kind == 1]) ** 2
    fan_power = np.sum(np.abs(fan_gain[beams.elevation_index == 0]) ** 2, axis=1)
    level = 10 * np.log10(fan_power / flat_power)
    dominated = specular.sum(axis=1) < 0.1 * flat_power  # beams the diffuse echoes dominate
    assert dominated.sum() > 40 and np.median(np.abs(level[dominated])) < 1.5
    # geometry: delay of the slant path from its point (x, y) and elevation
    r = np.linalg.norm(fan_paths.point[diffuse] - pose[:2], axis=1)
    dz = r * np.tan(fan_paths.elevation[diffuse])
    np.testing.assert_allclose(fan_paths.delay_s[diffuse], bistatic_slant_delay(r, dz, 0.05), rtol=1e-12)
    room = scene_from_mapping({**BOX, "radio": {"elevation_beams": 3},
                               "extrude": {"height_m": 2.6, "floor": "concrete", "ceiling": "concrete"}})
    paths = echo_paths(room, pose)
    for code, height in ((FLOOR_SEGMENT, 0.0), (CEILING_SEGMENT, 2.6)):
        on = paths.segment == code
        slant = C * paths.delay_s[on] / 2  # ≈ the slant range (b = 5 cm)
        assert on.sum() > 100
        np.testing.assert_allclose(1.5 + slant * np.sin(paths.elevation[on]), height, atol=2e-3)
    walls = (paths.kind == PathKind.DIFFUSE) & (paths.segment >= 0)
    r = np.linalg.norm(paths.point[walls] - pose[:2], axis=1)
    z = 1.5 + r * np.tan(paths.elevation[walls])
    assert z.min() >= 0.0 and z.max() <= 2.6  # the walls stop at the floor and the ceiling


@pytest.mark.parametrize("elevation_deg", [-11.0, -3.0, 0.0, 6.0, 13.0])
def test_height_between_the_rows(elevation_deg):
    """A point target 4 m away at elevation ε on the boresight column of 5 rows (every 7.2°): the rows'
    amplitude comparison puts it within 0.5° of ε (3.5 cm of height), on every row that detects it; the
    detecting row's own pointing alone would be up to 3.6° off."""
    radio = RadioConfig(elevation_beams=5, snr_db=30.0, isolation_db=400.0)
    sim = Simulator.from_radio(radio)
    beams = sim.beams
    rows = np.flatnonzero((beams.orientation == 0) & (beams.index == 0))
    sim = Simulator.from_radio(radio, rows=rows)
    eps = np.radians(elevation_deg)
    delay = bistatic_slant_delay(np.array([4.0 * np.cos(eps)]), np.array([4.0 * np.sin(eps)]), radio.array_baseline_m)
    paths = EchoPaths(delay, np.array([np.sqrt(noise_variance(radio) * 10 ** 3) / 8.0 + 0j]), np.zeros(1),
                      np.array([PathKind.SPECULAR], np.int8), np.full(1, -1), np.array([[4.0, 0.0]]),
                      elevation=np.array([eps]))
    capture = sim.capture_from_paths(paths, np.random.default_rng(3))
    scan = Receiver(radio, radio.hardware_delay_s).sense(capture).scan
    assert len(scan) >= 1
    np.testing.assert_allclose(scan.range_m, 4.0, atol=0.02)
    assert np.max(np.abs(np.degrees(scan.elevation_rad) - elevation_deg)) < 0.5
    np.testing.assert_allclose(scan.z, 4.0 * np.sin(eps), atol=0.035)


def test_scan_ply_carries_z_and_the_elevation_row(tmp_path):
    scan = Scan(np.array([4.0, 2.0, 3.0]), np.array([0.1, -2.0, 3.0]), np.array([0.0, -3.0, -9.0]),
                np.array([0, -5, 7]), np.array([0, 2, 3]), np.radians([10.0, 0.0, -20.0]), np.array([4, 0, -8]))
    write_scan(tmp_path / "s.ply", scan)
    back = read_scan(tmp_path / "s.ply")
    for name in ("range_m", "angle_rad", "elevation_rad"):
        np.testing.assert_allclose(getattr(back, name), getattr(scan, name), atol=1e-12)
    np.testing.assert_array_equal(back.elevation_beam, scan.elevation_beam)
    np.testing.assert_allclose(back.z, [4 * np.sin(np.radians(10)), 0.0, 3 * np.sin(np.radians(-20))], atol=1e-12)
    assert len(back.horizontal()) == 1 and back.horizontal().range_m[0] == 2.0
    assert read_map_points(tmp_path / "s.ply", horizontal=True).shape == (1, 2)
    assert read_map_points(tmp_path / "s.ply", dims=3).shape == (3, 3)


def test_leakage_calibration_keys_the_elevation_row():
    model = LeakageModel(np.array([0, 0]), np.array([3, 3]), np.array([1e-10, 2e-10]), np.array([1 + 0j, 2 + 0j]),
                         np.array([-4, 4]))
    back = LeakageModel.from_dict(model.to_dict())
    np.testing.assert_array_equal(back.elevation_index, [-4, 4])
    assert list(back.rows_of(np.array([0, 0]), np.array([3, 3]), elevation_index=np.array([4, -4]))) == [1, 0]
    with pytest.raises(ValueError, match="listed twice"):
        LeakageModel.from_dict({**model.to_dict(), "elevation_index": [1, 1]})
    flat_doc = LeakageModel(np.array([0, 1]), np.array([3, 3]), np.zeros(2), np.zeros(2, complex)).to_dict()
    assert "elevation_index" not in flat_doc  # a flat scan's file is as before
    np.testing.assert_array_equal(LeakageModel.from_dict(flat_doc).elevation_index, [0, 0])


def test_height_errors_against_a_box():
    """Points 3 cm above a table top and 5 cm below a ceiling: the errors are +0.03 and −0.05 m exactly;
    a point beside a vertical face counts only in the 3D distance."""
    names = ("wood",)
    mesh = Mesh.join([Mesh.box((0, 0, 0), (2, 1, 0.75), 0, names), Mesh.box((-5, -5, 2.8), (5, 5, 2.9), 0, names)])
    points = np.array([[1.0, 0.5, 0.78], [0.3, 0.2, 0.78], [-3.0, 2.0, 2.75], [2.2, 0.5, 0.3]])
    match = match_surfaces(points, mesh)
    np.testing.assert_allclose(match.height_error_m[:3], [0.03, 0.03, -0.05], atol=1e-9)
    assert not match.horizontal[3] and match.distance_m[3] == pytest.approx(0.2, abs=0.04)
    summary = height_error_summary(match)
    assert summary["points"] == 3 and set(summary["by_surface_height_m"]) == {"0.75", "2.8"}
