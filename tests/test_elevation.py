"""Elevation beams and 3D point clouds (issue #16): the UPA's separable codebook against its array factor,
the 2.5D caster's calibration and geometry, heights estimated between the rows, z through the files."""

import numpy as np
import pytest

from radioslam.antenna.codebook import ANY_ROW, BeamSet
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


def test_horizontal_row_is_the_flat_scans_channel():
    """Walls from the floor up, of no height or twice the arrays': the 2.5D channel's horizontal row is the
    flat caster's channel, its diffuse paths the flat rays in delay (1 µm) and phase (1 mrad) and within
    0.2 dB in power (the 3D lobe), and its response H on every horizontal beam within 0.2 dB, correlated
    ≥ 0.999."""
    from radioslam.nr.numerology import Numerology
    from radioslam.sim.channel import channel_response

    for extrude in (None, {"height_m": 3.0}):
        flat = scene_from_mapping({**BOX, "radio": {"isolation_db": 400}, **({"extrude": extrude} if extrude else {})})
        raised = scene_from_mapping({**BOX, "radio": {"isolation_db": 400, "elevation_beams": 5},
                                     **({"extrude": extrude} if extrude else {})})
        pose = flat.poses[0]
        flat_paths, fan_paths = echo_paths(flat, pose), echo_paths(raised, pose)
        level = fan_paths.row == 0
        assert level.sum() == np.sum(flat_paths.kind == PathKind.DIFFUSE)
        diffuse = flat_paths.kind == PathKind.DIFFUSE
        np.testing.assert_allclose(fan_paths.delay_s[level] * C, flat_paths.delay_s[diffuse] * C, atol=1e-6)  # 1 µm
        ratio = fan_paths.amplitude[level] / flat_paths.amplitude[diffuse]
        assert np.all(np.abs(20 * np.log10(np.abs(ratio))) < 0.2) and np.allclose(np.angle(ratio), 0.0, atol=1e-3)
        beams_flat, beams = BeamSet.from_config(flat.radio), BeamSet.from_config(raised.radio)
        p = Numerology.from_config(flat.radio).subcarrier_indices()
        h_flat = channel_response(beam_path_gains(beams_flat, flat_paths), flat_paths.delay_s, p, 120e3)
        h_fan = channel_response(beam_path_gains(beams, fan_paths)[beams.elevation_index == 0], fan_paths.delay_s,
                                 p, 120e3)
        power = 10 * np.log10(np.sum(np.abs(h_fan) ** 2, axis=1) / np.sum(np.abs(h_flat) ** 2, axis=1))
        corr = np.abs(np.sum(h_fan * h_flat.conj(), axis=1)) / (np.linalg.norm(h_fan, axis=1)
                                                                 * np.linalg.norm(h_flat, axis=1))
        assert np.max(np.abs(power)) < 0.2 and corr.min() > 0.999


def test_wall_columns_follow_the_rows_and_the_walls_height():
    """A wall column's path on row j lies on the wall (its delay the slant path to its point at the
    centroid ε_j), within the wall's height, its power the row's integral: converged in the quadrature,
    and raised rows see less of a low wall. The floor's and ceiling's echoes lie on them."""
    import radioslam.sim.elevated as elevated

    room = scene_from_mapping({**BOX, "radio": {"elevation_beams": 5},
                               "extrude": {"height_m": 2.6, "floor": "concrete", "ceiling": "concrete"}})
    pose = room.poses[0]
    paths = echo_paths(room, pose)
    walls = (paths.kind == PathKind.DIFFUSE) & (paths.segment >= 0)
    r = np.linalg.norm(paths.point[walls] - pose[:2], axis=1)
    dz = r * np.tan(paths.elevation[walls])
    np.testing.assert_allclose(paths.delay_s[walls], bistatic_slant_delay(r, dz, 0.05), rtol=1e-12)
    assert np.all((1.5 + dz >= 0.0) & (1.5 + dz <= 2.6))  # the walls stop at the floor and the ceiling
    assert set(paths.row[walls]) == {-8, -4, 0, 4, 8} and np.all(paths.row[~walls] == ANY_ROW)
    for code, height in ((FLOOR_SEGMENT, 0.0), (CEILING_SEGMENT, 2.6)):
        on = paths.segment == code
        slant = C * paths.delay_s[on] / 2  # ≈ the slant range (b = 5 cm)
        assert on.sum() > 100
        np.testing.assert_allclose(1.5 + slant * np.sin(paths.elevation[on]), height, atol=2e-3)
    # the quadrature: a step 4× finer moves no row's power by more than 0.01 dB
    coarse = elevated.wall_column_paths(room, pose, room.radio)
    step, elevated.WALL_STEP_DEG = elevated.WALL_STEP_DEG, elevated.WALL_STEP_DEG / 4
    try:
        fine = elevated.wall_column_paths(room, pose, room.radio)
    finally:
        elevated.WALL_STEP_DEG = step
    np.testing.assert_allclose(20 * np.log10(np.abs(fine[1] / coarse[1])), 0.0, atol=0.01)
    # the arrays 0.3 m above the floor: the rows below see little wall (the lowest 21 dB less than the
    # highest); halfway up, rows ±j see alike
    for height, lowest_db in ((0.3, -15.0), (1.5, 0.0)):
        scene = scene_from_mapping({**BOX, "radio": {"elevation_beams": 5, "height_m": height},
                                    "extrude": {"height_m": 3.0}})
        _, amp, _, _, _, _, row = elevated.wall_column_paths(scene, pose, scene.radio)
        power = {j: np.sum(np.abs(amp[row == j]) ** 2) for j in (-8, 8)}
        level = 10 * np.log10(power[-8] / power[8])
        assert level < lowest_db if lowest_db < 0 else abs(level) < 0.01


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


@pytest.mark.parametrize("elevations_deg", [(-60.0,), (-58.0, 58.0), (75.0,)])
def test_echoes_outside_the_rows_make_no_point(elevations_deg):
    """Echoes from outside the rows' span (±14.5° of 5 rows): a floor alone, or a floor and a ceiling at one
    slant range (the arrays halfway up), 40 dB above the noise on the rows' sidelobes. The beam-space fit
    over every elevation puts them outside each row's window, so no row makes a point of them; the same
    echoes within the span do (:func:`test_height_between_the_rows`). (Within about 35° beyond the span the
    rows' sidelobe magnitudes can look like a main lobe's: the 8 rows' pattern repeats its shape there.)"""
    radio = RadioConfig(elevation_beams=5, snr_db=30.0, isolation_db=400.0)
    beams = Simulator.from_radio(radio).beams
    sim = Simulator.from_radio(radio, rows=np.flatnonzero((beams.orientation == 0) & (beams.index == 0)))
    eps = np.radians(np.array(elevations_deg))
    slant = 1.8
    delay = bistatic_slant_delay(slant * np.cos(eps), slant * np.sin(eps), radio.array_baseline_m)
    sidelobe = np.max(beams.vertical_gain(eps))  # the strongest row's two-way vertical factor there
    amplitude = np.sqrt(noise_variance(radio) * 10 ** 4) / 8.0 / sidelobe
    rng = np.random.default_rng(5)
    paths = EchoPaths(delay, amplitude * np.exp(2j * np.pi * rng.random(len(eps))), np.zeros(len(eps)),
                      np.full(len(eps), PathKind.SPECULAR, np.int8), np.full(len(eps), -1),
                      np.column_stack([slant * np.cos(eps), np.zeros(len(eps))]), elevation=eps)
    result = Receiver(radio, radio.hardware_delay_s).sense(sim.capture_from_paths(paths, rng))
    assert np.any(result.valid)  # detected on the rows ...
    assert len(result.scan) == 0  # ... but not a point
