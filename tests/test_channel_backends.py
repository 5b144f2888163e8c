"""Channel backends (issue #16): the extruded 3D scene, the beamformer of per-element coefficients against
the array factor, the one-line errors, and (where Sionna RT is installed) the two backends cross-checked
on a single plate."""

import importlib.util
import os
import subprocess
import sys

import numpy as np
import pytest

from radioslam.antenna.codebook import BeamSet
from radioslam.config import RadioConfig
from radioslam.scene import SceneError, load_scene, scene_from_mapping
from radioslam.scene.extrude import extruded_mesh
from radioslam.sim import Simulator, beam_path_gains, echo_paths
from radioslam.sim.paths import PathKind
from radioslam.sim.sionna_channel import beam_gains, element_factor

C = 299_792_458.0
ROOM = {"version": 1, "name": "room",
        "walls": [{"points": [[-4, -3], [5, -3], [5, 3], [-4, 3], [-4, -3]], "material": "concrete"},
                  {"points": [[1, 0], [2, 1]], "material": "metal"}],
        "trajectory": {"poses": [[0.0, 0.0, 0.0]]}}


SIONNA_SKIP = ("Sionna RT is not usable here; to run these tests: pip install 'radioslam[sionna]' and "
               "apt install libllvm19 (or set DRJIT_LIBLLVM_PATH to an LLVM ≥ 16)")


def _sionna_available() -> bool:
    if importlib.util.find_spec("sionna") is None:
        return False
    try:
        from radioslam.sim.sionna_channel import import_sionna

        import_sionna()
        return True
    except Exception:
        return False


def test_extruded_mesh_areas_and_heights():
    scene = scene_from_mapping({**ROOM, "extrude": {"height_m": 2.5, "floor": "concrete", "ceiling": "drywall"}})
    mesh = extruded_mesh(scene)
    lengths = np.linalg.norm(scene.segments[:, 1] - scene.segments[:, 0], axis=1)
    area = mesh.area()
    walls = area[: 2 * len(lengths)].reshape(-1, 2).sum(axis=1)
    np.testing.assert_allclose(walls, 2.5 * lengths, rtol=1e-12)  # each wall segment × the height
    np.testing.assert_allclose(area[2 * len(lengths):].reshape(-1, 2).sum(axis=1), [9 * 6, 9 * 6])  # floor, ceiling
    assert set(np.unique(mesh.vertices[:, 2])) == {0.0, 2.5}
    names = [mesh.material_names[m] for m in mesh.face_material[-4:]]
    assert names == ["concrete", "concrete", "drywall", "drywall"]
    metal = mesh.of_material(scene.material_names.index("metal"))
    assert len(metal.faces) == 2 and metal.faces.max() == len(metal.vertices) - 1
    np.testing.assert_allclose(metal.area().sum(), 2.5 * np.sqrt(2))


@pytest.mark.parametrize("extra, field, reason", [
    ({"extrude": {"height_m": 2.5, "floor": "lava"}}, "extrude.floor", "unknown material 'lava'"),
    ({"extrude": {"height_m": 1.0}}, "radio.height_m", "not inside the walls"),
    ({"extrude": {"height_m": 0.0}}, "extrude.height_m", "greater than 0"),
    ({"materials": {"brick": {"reflectivity": 0.5, "scattering": 0.4, "directivity": 4, "itu": "lava"}}},
     "materials.brick.itu", "'concrete'"),
])
def test_extrusion_errors_name_the_field(extra, field, reason):
    with pytest.raises(SceneError) as info:
        scene_from_mapping({**ROOM, **extra}, source="room.yaml")
    assert info.value.field == field and reason in info.value.reason


def _plane_wave_coefficients(theta: float, n: int, gain: complex = 1.0) -> np.ndarray:
    """A[m, n] of a far echo from azimuth θ (array frame) for two rows of n elements at λ/2 centred on the
    array, elements ascending along +y (Sionna's PlanarArray): e^{jk u·(r_m + r_n)}."""
    y = (np.arange(n) - (n - 1) / 2) * 0.5  # wavelengths
    phase = np.exp(2j * np.pi * y * np.sin(theta))
    return gain * np.outer(phase, phase)[None]


@pytest.mark.parametrize("theta_deg", [0.0, 12.0, -31.0, 44.0])
def test_beamformer_of_element_coefficients_is_the_array_factor(theta_deg):
    """w̃^H A w̃^* of a plane wave's per-element coefficients has the magnitude of the codebook's two-way
    gain |w^H a(θ)|² (eq. (4)) on every beam of the orientation, and the beam pointing at θ is the largest."""
    radio = RadioConfig(element_exponent=0.0)
    beams = BeamSet.from_config(radio)
    theta = np.radians(theta_deg)
    gains = beam_gains(beams, _plane_wave_coefficients(theta, radio.array_elements), orientation=0)
    expected = beams.two_way_gain(np.array([theta]))
    rows = beams.orientation == 0
    assert gains.shape == (rows.sum(), 1) and gains.dtype == np.complex64  # Sionna's single precision
    np.testing.assert_allclose(np.abs(gains[:, 0]), expected[rows, 0], rtol=2e-6, atol=1e-6)
    assert abs(beams.angle[rows][np.argmax(np.abs(gains[:, 0]))] - theta) <= np.radians(1.0)


def test_elevation_and_element_factors():
    eps = np.radians(np.array([0.0, 3.0, 10.0, -25.0, 60.0]))
    rows = 8
    flat = BeamSet.from_config(RadioConfig())
    direct = np.abs(np.exp(1j * np.pi * np.arange(rows)[:, None] * np.sin(eps)).sum(axis=0)) / rows
    np.testing.assert_allclose(flat.vertical_factor(eps)[0], direct, rtol=1e-12, atol=1e-15)
    assert flat.vertical_factor(np.zeros(1))[0, 0] == pytest.approx(1.0, abs=1e-15)
    # half power at about ±6.4° for 8 rows (0.886 λ/(N d) rad)
    assert flat.vertical_factor(np.radians([6.35]))[0, 0] ** 2 == pytest.approx(0.5, abs=0.01)
    # a raised row j steers the same sum: |Σ_r e^{jπr(sin ε − 2j/2^M)}|/N, peak 1 at sin ε = 2j/64
    raised = BeamSet.from_config(RadioConfig(elevation_beams=5))
    j = raised.elevation_index[:, None]
    phase = np.pi * np.arange(rows)[:, None, None] * (np.sin(eps) - 2 * j / 64)
    steered = np.abs(np.exp(1j * phase).sum(axis=0)) / rows
    np.testing.assert_allclose(raised.vertical_factor(eps), steered, rtol=1e-12, atol=1e-15)
    assert raised.vertical_factor(raised.elevation) .diagonal() == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(element_factor(np.radians([0.0, 60.0, 100.0]), np.zeros(3), 2.0), [1.0, 0.5, 0.0],
                               atol=1e-15)


def test_builtin_backend_is_the_caster():
    """The default backend is today's caster, path for path."""
    scene = load_scene("paper-cnv")
    sim = Simulator.from_scene(scene)
    ours, direct = sim.channel.paths(scene.poses[3]), echo_paths(scene, scene.poses[3], scene.radio)
    for field in ("delay_s", "amplitude", "angle", "kind", "segment"):
        np.testing.assert_array_equal(getattr(ours, field), getattr(direct, field))
    assert ours.beam_gain is None


@pytest.mark.skipif(_sionna_available(), reason="Sionna RT is installed here")
def test_sionna_missing_is_one_line(tmp_path):
    scene = tmp_path / "room.yaml"
    scene.write_text("version: 1\nname: room\nwalls:\n  - {points: [[-4, -3], [5, -3], [5, 3], [-4, 3], [-4, -3]], "
                     "material: concrete}\ntrajectory: {poses: [[0, 0, 0]]}\nextrude: {height_m: 3.0}\n")
    out = subprocess.run([sys.executable, "-m", "radioslam.cli", "simulate", str(scene), "--out", str(tmp_path / "run"),
                          "--channel", "sionna"], capture_output=True, text=True,
                         env={**os.environ, "PYTHONWARNINGS": "ignore"})
    assert out.returncode == 2
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and "--channel" in lines[0] and "pip install 'radioslam[sionna]'" in lines[0]
    assert not (tmp_path / "run").exists()  # refused before anything is written


@pytest.mark.skipif(not _sionna_available(), reason=SIONNA_SKIP)
@pytest.mark.parametrize("yaw", [0.0, 0.3, 2.0])
def test_sionna_matches_the_caster_on_a_plate(yaw):
    """A metal plate 3 m ahead: on the beams where the specular echo is the strongest path in both
    backends, its delay agrees within 1 mm of path (2R/c, R = 3 m) and its gain within 0.5 dB, and the
    best beam is the same."""
    scene = scene_from_mapping({"version": 1, "name": "plate", "walls": [{"points": [[3, -1], [3, 1]],
                                                                         "material": "metal"}],
                                "trajectory": {"poses": [[0, 0, yaw]]}, "extrude": {"height_m": 3.0}})
    beams = BeamSet.from_config(scene.radio)
    paths = {kind: Simulator.from_scene(scene, channel=kind).channel.paths(scene.poses[0], leakage=False)
             for kind in ("builtin", "sionna")}
    gains = {kind: beam_path_gains(beams, p) for kind, p in paths.items()}
    strongest = {kind: np.argmax(np.abs(g), axis=1) for kind, g in gains.items()}
    specular = np.ones(len(beams), bool)
    for kind, p in paths.items():
        specular &= p.kind[strongest[kind]] == PathKind.SPECULAR
    assert specular.sum() >= 5
    delay = {kind: paths[kind].delay_s[strongest[kind][specular]] for kind in paths}
    np.testing.assert_allclose(delay["sionna"] * C, delay["builtin"] * C, atol=1e-3)
    np.testing.assert_allclose(delay["builtin"] * C, 2 * np.hypot(3.0, scene.radio.array_baseline_m / 2), atol=1e-9)
    rows = np.flatnonzero(specular)
    level = {kind: 20 * np.log10(np.abs(gains[kind][rows, strongest[kind][rows]])) for kind in paths}
    np.testing.assert_allclose(level["sionna"], level["builtin"], atol=0.5)
    assert np.argmax(np.abs(gains["sionna"]).max(axis=1)) == np.argmax(np.abs(gains["builtin"]).max(axis=1))


def _write_mitsuba(folder, height=3.0):
    """A Mitsuba scene of the extruded ROOM (one PLY per material), as Sionna's Blender export writes it."""
    from plyfile import PlyData, PlyElement

    scene = scene_from_mapping({**ROOM, "extrude": {"height_m": height, "floor": "concrete"}})
    mesh = extruded_mesh(scene)
    (folder / "meshes").mkdir()
    shapes, bsdfs = [], []
    for m in np.unique(mesh.face_material):
        part, name = mesh.of_material(int(m)), scene.material_names[m]
        vertex = np.array([tuple(v) for v in part.vertices], dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
        face = np.array([(list(f),) for f in part.faces], dtype=[("vertex_indices", "i4", (3,))])
        PlyData([PlyElement.describe(vertex, "vertex"), PlyElement.describe(face, "face")]).write(
            str(folder / "meshes" / f"{name}.ply"))
        itu = scene.materials[m].itu.value
        bsdfs.append(f'<bsdf type="twosided" id="mat-itu_{itu}"><bsdf type="principled"/></bsdf>')
        shapes.append(f'<shape type="ply" id="{name}"><string name="filename" value="meshes/{name}.ply"/>'
                      f'<ref id="mat-itu_{itu}" name="bsdf"/></shape>')
    (folder / "room.xml").write_text(f'<scene version="2.1.0">{"".join(bsdfs)}{"".join(shapes)}</scene>')
    return scene


def test_mitsuba_scene_is_sliced_at_the_terminals_height(tmp_path):
    """A Mitsuba scene's walls in 2D are its mesh cut at radio.height_m: the extruded room's own segments
    (each wall cut as its two triangles, so every segment lies on a true wall, and they cover its length);
    the floor does not cross that height. The scene file's folder resolves the XML."""
    walled = _write_mitsuba(tmp_path)
    (tmp_path / "room.yaml").write_text("version: 1\nname: room-xml\nmitsuba: room.xml\n"
                                        "trajectory: {poses: [[0, 0, 0]]}\n")
    from radioslam.scene import load_scene_file

    scene = load_scene_file(tmp_path / "room.yaml")
    assert scene.spec.mitsuba == str((tmp_path / "room.xml").resolve())
    from radioslam.scene.geometry import point_segment_distance

    assert len(scene.segments) == len(walled.segments)  # a wall's two triangles joined into one segment again
    ends = scene.segments.reshape(-1, 2)
    assert point_segment_distance(ends, walled.segments).min(axis=1).max() < 1e-5
    lengths = lambda seg: np.linalg.norm(seg[:, 1] - seg[:, 0], axis=1).sum()  # noqa: E731
    assert lengths(scene.segments) == pytest.approx(lengths(walled.segments), rel=1e-6)
    assert {scene.materials[m].itu.value for m in scene.segment_material} == {"concrete", "metal"}
    # the built-in caster runs on the slice: the same specular echoes as the 2D room
    ours = Simulator.from_scene(scene).channel.paths(scene.poses[0])
    theirs = echo_paths(walled, walled.poses[0], walled.radio)
    spec = lambda p: np.sort(p.delay_s[p.kind == PathKind.SPECULAR])  # noqa: E731
    np.testing.assert_allclose(spec(ours)[:4], spec(theirs)[:4], atol=1e-14)


@pytest.mark.parametrize("xml, reason", [
    ("<scene><shape type='obj' id='a'/></scene>", "only ply meshes"),
    ("<scene><bsdf type='itu-radio-material' id='m'><string name='type' value='lava'/></bsdf></scene>",
     "unknown ITU material type"),
    ("<scene><bsdf type='twosided' id='mat-itu_lava'/></scene>", "unknown ITU material type"),
    ("<scene><shape type='ply' id='a'><string name='filename' value='x.ply'/></shape></scene>", "needs a filename"),
    ("<scene", "not XML"),
])
def test_bad_mitsuba_scene_is_one_error(tmp_path, xml, reason):
    (tmp_path / "bad.xml").write_text(xml)
    with pytest.raises(SceneError) as info:
        scene_from_mapping({"version": 1, "name": "x", "mitsuba": str(tmp_path / "bad.xml"),
                            "trajectory": {"poses": [[0, 0, 0]]}})
    assert reason in info.value.reason and str(tmp_path / "bad.xml") in info.value.one_line()


@pytest.mark.skipif(not _sionna_available(), reason=SIONNA_SKIP)
def test_sionna_reads_the_mitsuba_scene_as_the_extruded_one(tmp_path):
    """The same room as a Mitsuba file and as an extruded YAML scene: Sionna's specular echoes agree."""
    walled = _write_mitsuba(tmp_path)
    from_xml = scene_from_mapping({"version": 1, "name": "x", "mitsuba": str(tmp_path / "room.xml"),
                                   "trajectory": {"poses": [[0.5, 0.2, 0.4]]}})
    extruded = scene_from_mapping({**ROOM, "extrude": walled.spec.extrude.model_dump(),
                                   "trajectory": {"poses": [[0.5, 0.2, 0.4]]}})
    delays = []
    for scene in (from_xml, extruded):
        paths = Simulator.from_scene(scene, channel="sionna").channel.paths(scene.poses[0], leakage=False)
        delays.append(np.unique(np.round(paths.delay_s[paths.kind == PathKind.SPECULAR] * C, 6)))
    assert len(delays[0]) >= 4
    np.testing.assert_array_equal(delays[0], delays[1])


@pytest.mark.skipif(not _sionna_available(), reason=SIONNA_SKIP)
def test_run_on_the_sionna_channel_end_to_end(tmp_path):
    """`radioslam run --channel sionna` on an extruded room: scans, a trajectory and metrics, the channel
    in run.json."""
    import json

    scene = tmp_path / "room.yaml"
    scene.write_text("version: 1\nname: room\nwalls:\n  - {points: [[-4, -3], [5, -3], [5, 3], [-4, 3], [-4, -3]], "
                     "material: concrete}\n  - {points: [[1, 1], [2, 2]], material: metal}\ntrajectory: "
                     "{poses: [[0, 0, 0], [0.3, 0, 0.05], [0.6, 0.1, 0.1]]}\nextrude: {height_m: 3.0}\n")
    out = tmp_path / "run"
    done = subprocess.run([sys.executable, "-m", "radioslam.cli", "run", str(scene), "--out", str(out), "--channel",
                           "sionna", "--json"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-2000:]
    metrics = json.loads(done.stdout)
    assert metrics["poses"] == 3 and metrics["ate_rmse_m"] < 0.1
    manifest = json.loads((out / "run.json").read_text())
    assert manifest["stages"]["simulate"]["settings"]["channel"] == "sionna"
    assert len(list((out / "scans").glob("*.ply"))) == 3
    # each pose's trace kept in traces/, and a new run of the directory (another seed) reads them back
    traces = {f.name: f.stat().st_mtime_ns for f in (out / "traces").glob("*.npz")}
    assert len(traces) == 3
    done = subprocess.run([sys.executable, "-m", "radioslam.cli", "simulate", str(scene), "--out", str(out),
                           "--channel", "sionna", "--seed", "4", "--save-iq"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-2000:]
    assert {f.name: f.stat().st_mtime_ns for f in (out / "traces").glob("*.npz")} == traces
    assert not list((out / "scans").glob("*.ply")) and len(list((out / "captures").glob("*.sigmf-data"))) == 3


def test_collinear_pieces_join_and_corners_stay():
    """A wall cut into three pieces, met in any order, is one segment again; a corner's two walls and two
    materials on one line stay apart."""
    from radioslam.scene.mitsuba import merge_collinear

    pieces = np.array([[[1.0, 0], [2, 0]], [[0, 0], [1, 0]], [[2, 2], [2, 0]], [[3, 0], [2, 0]], [[3, 0], [4, 0]]])
    material = np.array([0, 0, 0, 0, 1])
    segments, kept = merge_collinear(pieces, material)
    assert len(segments) == 3
    joined = segments[np.argmax(np.linalg.norm(segments[:, 1] - segments[:, 0], axis=1))]
    np.testing.assert_allclose(sorted(joined[:, 0]), [0.0, 3.0])
    assert sorted(kept.tolist()) == [0, 0, 1]


def test_a_memory_estimate_builds_no_channel(tmp_path):
    """A Mitsuba scene with a class the caster lacks: the memory estimate runs whatever the channel (no
    backend is built for it), the built-in caster refuses in one line naming the scene, and Sionna is
    not refused by the caster's check."""
    from radioslam.sim.channel_backend import check_channel

    _write_mitsuba(tmp_path)
    xml = (tmp_path / "room.xml").read_text().replace("mat-itu_concrete", "mat-itu_brick")
    (tmp_path / "room.xml").write_text(xml)
    scene = scene_from_mapping({"version": 1, "name": "x", "mitsuba": str(tmp_path / "room.xml"),
                                "trajectory": {"poses": [[0, 0, 0]]}})
    assert Simulator.from_scene(scene, channel="sionna").memory().total > 0
    from radioslam.sim.errors import SimulationError

    with pytest.raises(SimulationError) as info:
        check_channel("builtin", scene, "room.yaml")
    assert info.value.file == "room.yaml" and "brick" in info.value.reason


def test_trace_cache_round_trip_and_damaged_entries(tmp_path):
    """Arrays stored under a key read back bit for bit; a truncated archive or a missing one is a miss
    (traced again), not an error; a key that is no hex digest is refused (it names a file)."""
    from radioslam.io.trace_cache import TraceCache

    cache, key = TraceCache(tmp_path / "traces"), "ab" * 32
    arrays = {"tau": np.random.default_rng(0).random((4, 7)), "coefficients": np.ones((4, 8, 8, 7), np.complex64),
              "diffuse": np.zeros((4, 7), bool)}
    assert cache.load(key) is None
    cache.store(key, arrays)
    back = cache.load(key)
    assert back.keys() == arrays.keys() and cache.hits == 1 and cache.stored == 1
    for name in arrays:
        assert back[name].dtype == arrays[name].dtype
        np.testing.assert_array_equal(back[name], arrays[name])
    path = cache.path(key)
    path.write_bytes(path.read_bytes()[:100])
    assert cache.load(key) is None
    assert [p.name for p in cache.directory.iterdir()] == [path.name]  # no temporary left
    with pytest.raises(ValueError):
        cache.path("../x")


@pytest.mark.skipif(not _sionna_available(), reason=SIONNA_SKIP)
def test_sionna_trace_is_read_back_from_the_cache(tmp_path):
    """A second channel on the same cache traces nothing and gives the same paths bit for bit (a Sionna
    trace itself varies by a path or so from call to call); the key changes with the pose, the scene's
    materials and the carrier, not with the codebook (applied after the trace)."""
    from radioslam.io.trace_cache import TraceCache
    from radioslam.sim.sionna_channel import SionnaChannel

    spec = {**ROOM, "extrude": {"height_m": 3.0}, "radio": {"sionna_samples": 5000}}
    scene = scene_from_mapping(spec)
    first = SionnaChannel(scene, scene.radio, cache=TraceCache(tmp_path))
    paths = first.paths(scene.poses[0])
    cache = TraceCache(tmp_path)
    again = SionnaChannel(scene, scene.radio, cache=cache)
    again.trace = None  # a trace would fail: every array must come from the cache
    repeat = again.paths(scene.poses[0])
    assert cache.hits == 1 and len(list(tmp_path.glob("*.npz"))) == 1
    for name in ("delay_s", "amplitude", "angle", "kind", "point", "beam_gain"):
        np.testing.assert_array_equal(getattr(repeat, name), getattr(paths, name))
    key = first.trace_key(scene.poses[0])
    assert first.trace_key(scene.poses[0] + [0, 0, 1e-9]) != key
    rough = {"reflectivity": 0.5, "scattering": 0.5, "directivity": 3.0, "itu": "concrete"}
    scattering = scene_from_mapping({**spec, "materials": {"concrete": rough}})
    assert SionnaChannel(scattering, scattering.radio).trace_key(scene.poses[0]) != key
    carrier = scene.with_radio(carrier_hz=27e9)
    assert SionnaChannel(carrier, carrier.radio).trace_key(scene.poses[0]) != key
    rows = scene_from_mapping({**spec, "radio": {"sionna_samples": 5000, "element_exponent": 2.0}})
    assert SionnaChannel(rows, rows.radio).trace_key(scene.poses[0]) == key


SIONNA_POSE_MEMORY = """
import numpy as np
from radioslam.choices import ChannelKind
from radioslam.scene import scene_from_mapping
from radioslam.sim import Simulator
room = {ROOM!r}
scene = scene_from_mapping({{**room, "extrude": {{"height_m": 3.0, "floor": "concrete", "ceiling": "concrete"}},
                            "radio": {{"sionna_samples": 30000, "elevation_beams": 3}}}})
sim = Simulator.from_scene(scene, channel=ChannelKind.SIONNA)
def peak():  # this process's resident high-water mark (getrusage's would carry the forking parent's)
    line = next(x for x in open("/proc/self/status") if x.startswith("VmHWM:"))
    return int(line.split()[1]) * 1024
before = peak()
sim.simulate_pose(0, np.random.default_rng(0))
grown = peak() - before
print(grown, sim.memory().total, sim.memory().parts["ray tracer"][0])
"""


@pytest.mark.skipif(not _sionna_available(), reason=SIONNA_SKIP)
@pytest.mark.skipif(not os.path.exists("/proc/self/status"), reason="reads the resident peak from /proc")
def test_sionna_pose_memory_is_within_its_estimate():
    """--max-memory's estimate of a Sionna pose (its trace, outside Python's allocator, and the beams ×
    paths gains) bounds the resident memory the pose adds (a closed room: the most paths a sample gives),
    and is not a wild bound."""
    out = subprocess.run([sys.executable, "-c", SIONNA_POSE_MEMORY.format(ROOM=ROOM)], capture_output=True,
                         text=True, timeout=300, check=True)
    grown, estimate, tracer = map(int, out.stdout.split())
    assert tracer > 0 and grown <= estimate <= 4 * grown
