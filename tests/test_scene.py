"""Scene files ★ (DESIGN.md §4): validation, errors, built-ins, YAML round trip."""

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import trapezoid

from radioslam.scene import (
    BUILTIN_MATERIALS,
    BUILTIN_SCENES,
    SceneError,
    builtin_scene,
    load_scene,
    scene_from_mapping,
    scene_to_yaml,
)
from radioslam.scene.materials import Material

GOOD = {
    "version": 1, "name": "t",
    "walls": [{"points": [[-5, -5], [5, -5], [5, 5], [-5, 5], [-5, -5]], "material": "concrete"}],
    "trajectory": {"poses": [[0.0, 0.0, 0.0], [1.0, 0.0, 0.5]]},
}


def _variant(**changes):
    data = yaml.safe_load(yaml.safe_dump(GOOD))
    data.update(changes)
    return data


@pytest.mark.parametrize("data, field, reason", [
    (_variant(colour="red"), "colour", "unknown key"),
    ({k: v for k, v in GOOD.items() if k != "walls"}, "walls", "required key is missing"),
    (_variant(walls=[{"points": [[0, 0]], "material": "concrete"}]), "walls[0].points", "at least 2 points"),
    (_variant(walls=[{"points": [[0, 0], [1, 0]], "material": "unobtainium"}]), "walls[0].material",
     "unknown material 'unobtainium'"),
    (_variant(trajectory={"poses": [[4.85, 0.0, 0.0]]}), "trajectory.poses[0]", "closer than 0.2 m"),
    (_variant(trajectory={"circle": {"center": [0, 0], "radius": 4.9, "poses": 8}}), "trajectory.circle",
     "closer than 0.2 m"),
    (_variant(trajectory={"circle": {"center": [0, 0], "radius": 1, "poses": 8}, "poses": [[0, 0, 0]]}),
     "trajectory", "exactly one"),
    (_variant(version=2), "version", "Input should be 1"),
    (_variant(radio={"snr_db": "loud"}), "radio.snr_db", "valid number"),
    (_variant(radio={"snr": 3}), "radio.snr", "unknown key"),
    (_variant(materials={"x": {"reflectivity": 0.9, "scattering": 0.1, "directivity": 2, "transmission": 0.9}}),
     "materials.x", "exceeds 1"),
    (_variant(walls=[{"points": [[0, 0], [0, 0]], "material": "metal"}]), "walls[0].points", "zero-length"),
    ([1, 2], "(top level)", "must be a mapping"),
    (_variant(radio={"elevation_beams": 4}), "radio", "must be odd"),
    (_variant(radio={"elevation_beams": 13}), "radio", "outside the visible region"),
    (_variant(radio={"subcarrier_spacing_hz": 60e3}), "radio", "120 kHz"),
    # bounds before work (issue #15): a building, not a continent; a radio this machine can simulate
    (_variant(trajectory={"poses": [[2e4, 0.0, 0.0]]}), "trajectory.poses[0][0]", "less than or equal to 10000"),
    (_variant(walls=[{"points": [[x / 10, 0] for x in range(20_002)], "material": "metal"}]), "(top level)",
     "20,001 wall segments: at most 20,000"),
    (_variant(radio={"fft_size": 2**24}), "radio.fft_size", "less than or equal to 4096"),
    (_variant(radio={"snr_db": 1e9}), "radio.snr_db", "less than or equal to 400"),
])
def test_scene_errors_name_field_and_reason(data, field, reason):
    with pytest.raises(SceneError) as info:
        scene_from_mapping(data, "room.yaml")
    err = info.value
    assert err.file == "room.yaml" and err.field == field and reason in err.reason
    assert "\n" not in err.one_line() and err.one_line().startswith(f"room.yaml: {field}: ")


def test_file_errors(tmp_path):
    with pytest.raises(SceneError, match="no such file"):
        load_scene(tmp_path / "missing.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("walls: [unclosed\n")
    with pytest.raises(SceneError, match="not valid YAML") as info:
        load_scene(bad)
    assert info.value.field.startswith("line ")


def test_custom_material_and_circle(tmp_path):
    data = _variant(materials={"brick": {"reflectivity": 0.5, "scattering": 0.4, "directivity": 4}},
                    walls=[{"points": [[-5, -5], [5, -5], [5, 5]], "material": "brick"}],
                    trajectory={"circle": {"center": [0, 0], "radius": 2, "poses": 4, "heading": "fixed"}})
    scene = scene_from_mapping(data)
    assert scene.material_names[scene.segment_material[0]] == "brick"
    assert np.allclose(scene.poses, [[2, 0, 0], [0, 2, 0], [-2, 0, 0], [0, -2, 0]], atol=1e-12)


def test_circle_heading_is_tangent():
    scene = builtin_scene("paper-cnv")
    assert scene.poses.shape == (60, 3)
    assert np.allclose(np.hypot(scene.poses[:, 0], scene.poses[:, 1]), 5.0)
    step = np.diff(scene.poses[:, :2], axis=0)
    travel = np.arctan2(step[:, 1], step[:, 0])
    # the chord direction lies half a step (3°) past the tangent at the start of the step
    assert np.allclose(np.angle(np.exp(1j * (travel - scene.poses[:-1, 2]))), np.pi / 60, atol=1e-9)


def test_yaml_round_trip_keeps_every_field(tmp_path):
    for name in BUILTIN_SCENES:
        scene = builtin_scene(name)
        path = tmp_path / f"{name}.yaml"
        path.write_text(scene_to_yaml(scene))
        again = load_scene(path)
        assert again.spec == scene.spec
        assert np.array_equal(again.segments, scene.segments)


def test_builtins_match_their_description():
    cnv = builtin_scene("paper-cnv")
    room = cnv.segments[cnv.segment_wall == 0]
    assert np.ptp(room[..., 0]) == 16 and np.ptp(room[..., 1]) == 16
    letters = cnv.segments[cnv.segment_wall > 0]
    assert np.all(np.abs(letters) <= 2.5) and len(set(cnv.segment_wall[cnv.segment_wall > 0])) == 3
    plate = builtin_scene("single-plate:6.4")
    assert np.allclose(plate.segments, [[[6.4, -0.5], [6.4, 0.5]]])
    door = builtin_scene("glass-door")
    assert np.isclose(door.segments[..., 0].max(), 15.0)
    with pytest.raises(SceneError):
        builtin_scene("single-plate:abc")
    with pytest.raises(SceneError):
        builtin_scene("paper-cnv:3")


def test_paper_cnv_laps_walks_the_room_again_and_again_never_retracing_a_lap():
    """paper-cnv's room and SNR, 60 poses a lap on a radius wandering 5 ± 0.25 m, the heading the path's
    tangent; the lap count is the argument (1 … 100), anything else one SceneError naming it."""
    laps = builtin_scene("paper-cnv-laps:3")
    cnv = builtin_scene("paper-cnv")
    assert len(laps.poses) == 180 and np.array_equal(laps.segments, cnv.segments)
    assert laps.radio.snr_db == cnv.radio.snr_db
    radius = np.hypot(laps.poses[:, 0], laps.poses[:, 1])
    assert 4.75 - 1e-9 <= radius.min() < 4.8 and 5.2 < radius.max() <= 5.25 + 1e-9
    step = np.diff(laps.poses[:, :2], axis=0)
    assert np.all(np.abs(np.linalg.norm(step, axis=1) - 2 * np.pi * 5 / 60) < 0.03)
    # the chord of each step runs along the mean of its two tangents (an arc: the tangent turns uniformly)
    travel = np.arctan2(step[:, 1], step[:, 0])
    mean = laps.poses[:-1, 2] + np.angle(np.exp(1j * np.diff(laps.poses[:, 2]))) / 2
    assert np.abs(np.angle(np.exp(1j * (travel - mean)))).max() < 1e-3
    # the same place of the room, lap after lap, a different radius
    assert np.abs(radius[0] - radius[60]) > 0.05 and np.abs(radius[60] - radius[120]) > 0.05
    assert len(builtin_scene("paper-cnv-laps").poses) == 240
    for bad in ("paper-cnv-laps:0", "paper-cnv-laps:2.5", "paper-cnv-laps:x", "glass-door:2"):
        with pytest.raises(SceneError) as err:
            builtin_scene(bad)
        assert err.value.field == "(argument)"


def test_directive_lobe_is_normalized_and_falls_off_with_incidence():
    for name, m in BUILTIN_MATERIALS.items():
        x = np.linspace(-np.pi, np.pi, 200_001)
        lobe = (2 * np.pi / m.lobe_norm) * np.cos(x / 2) ** (2 * m.directivity)
        assert trapezoid(lobe, x) / (2 * np.pi) == pytest.approx(1.0, rel=1e-6), name
        values = m.backscatter_lobe(np.radians([0, 20, 45, 80]))
        assert np.all(np.diff(values) < 0), name
    assert Material(0.5, 0.5, 0.0, 0.0).backscatter_lobe(np.array([0.3])) == pytest.approx(1.0)


_coord = st.floats(-20, 20, allow_nan=False).map(lambda v: round(v, 3))


@st.composite
def _scenes(draw):
    walls = []
    for _ in range(draw(st.integers(1, 4))):
        pts = draw(st.lists(st.tuples(_coord, _coord), min_size=2, max_size=5, unique=True))
        pts = [p for i, p in enumerate(pts) if i == 0 or p != pts[i - 1]]
        if len(pts) < 2:
            pts = [(0.0, 30.0), (1.0, 30.0)]
        walls.append({"points": [list(p) for p in pts], "material": draw(st.sampled_from(sorted(BUILTIN_MATERIALS)))})
    pose = [draw(st.floats(-50, 50)), 60.0, draw(st.floats(-3.1, 3.1))]  # clear of every wall
    radio = {"snr_db": draw(st.floats(-20, 40)), "hardware_delay_s": draw(st.floats(0, 1e-4))}
    return {"version": 1, "name": draw(st.text(min_size=1, max_size=12)), "walls": walls,
            "trajectory": {"poses": [pose]}, "radio": radio}


@given(_scenes())
@settings(max_examples=40, deadline=None)
def test_any_valid_scene_survives_the_yaml_round_trip(tmp_path_factory, data):
    scene = scene_from_mapping(data)
    path = tmp_path_factory.mktemp("s") / "scene.yaml"
    path.write_text(scene_to_yaml(scene), encoding="utf-8")
    again = load_scene(path)
    assert again.spec == scene.spec
    assert np.array_equal(again.segments, scene.segments) and np.array_equal(again.poses, scene.poses)
