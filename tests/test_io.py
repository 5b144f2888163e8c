"""SigMF and TUM round trips; bad recordings fail with file, field and reason."""

import json

import numpy as np
import pytest
from evo.tools import file_interface
from hypothesis import given, settings
from hypothesis import strategies as st
from sigmf import sigmffile

from radioslam.capture import CaptureError, CaptureMode
from radioslam.io import SigMFError, TumError, read_capture, read_tum, write_capture, write_tum
from radioslam.io.sigmf_io import data_path, meta_path
from radioslam.scene import builtin_scene
from radioslam.sim import Simulator

FIELDS = ("samples", "tx_bits", "orientation", "beam_index", "beam_angle_rad", "ssb_index", "symbol_indices")


@pytest.fixture(scope="module")
def capture():
    return Simulator.from_scene(builtin_scene("paper-cnv")).simulate_pose(5, np.random.default_rng(9))


@pytest.fixture
def written(capture, tmp_path):
    return write_capture(capture, tmp_path / "0005")


def test_sigmf_round_trip_is_bit_exact(capture, written):
    back = read_capture(written)
    for name in FIELDS:
        assert np.array_equal(getattr(back, name), getattr(capture, name)), name
    assert back.samples.dtype == np.complex64
    assert back.radio == capture.radio and back.pose_index == 5 and back.mode is CaptureMode.WAVEFORM
    assert not list(written.parent.glob(".*tmp"))  # nothing half-written left behind


def test_sigmf_metadata_passes_the_sigmf_validator(capture, written):
    record = sigmffile.fromfile(str(written))  # checks the data file's SHA-512 too
    record.validate()
    meta = json.loads(written.read_text())
    g = meta["global"]
    assert g["core:sample_rate"] == 122.88e6 and g["core:datatype"] == "cf32_le"
    assert g["radioslam:carrier_hz"] == 28e9 and g["radioslam:codebook_bits"] == 6
    assert g["radioslam:array_size"] == [8, 8] and g["radioslam:hardware_delay_s"] == 32e-6
    assert meta["captures"][0]["core:frequency"] == 28e9
    ann = meta["annotations"]
    assert len(ann) == 188
    assert ann[0]["radioslam:beam_index"] == -23 and len(ann[0]["radioslam:symbol_indices"]) == 13
    assert {e["name"] for e in g["core:extensions"]} == {"radioslam"}


def _edit_meta(path, change):
    meta = json.loads(path.read_text())
    change(meta)
    path.write_text(json.dumps(meta))


@pytest.mark.parametrize("change, field, reason", [
    (lambda m: m["annotations"].pop(), "annotations", "expected 188 beam annotations, found 187"),
    (lambda m: m["global"].update({"core:sample_rate": 61.44e6}), "global.core:sample_rate", "does not match"),
    (lambda m: m["annotations"][3].pop("radioslam:beam_index"), "annotations[3].radioslam:beam_index", "missing"),
    (lambda m: m["annotations"][2].update({"radioslam:tx_bits": "%%%"}), "annotations[2].radioslam:tx_bits",
     "base64"),
    (lambda m: [m["global"].pop(k) for k in ("radioslam:radio", "radioslam:carrier_hz")],
     "global.radioslam:carrier_hz", "missing"),
])
def test_bad_metadata_is_named(written, change, field, reason):
    _edit_meta(written, change)
    with pytest.raises(SigMFError) as info:
        read_capture(written)
    assert info.value.field == field and reason in info.value.reason


def test_truncated_data_file(written):
    data = data_path(str(written)[: -len(".sigmf-meta")])
    raw = data.read_bytes()
    data.write_bytes(raw[: len(raw) - 800])
    with pytest.raises(SigMFError, match="truncated") as info:
        read_capture(written)
    assert info.value.file == str(data)


def test_nan_samples_name_the_beam(capture, tmp_path):
    base = tmp_path / "nan"
    write_capture(capture, base)
    raw = np.fromfile(data_path(base), dtype="<c8")
    raw[17 * capture.samples.shape[1] + 100] = np.nan
    raw.tofile(data_path(base))
    _edit_meta(meta_path(base), lambda m: m["global"].pop("core:sha512"))
    with pytest.raises(CaptureError, match="NaN") as info:
        read_capture(base)
    assert info.value.field.startswith("beam 17")


def test_missing_files(tmp_path):
    with pytest.raises(SigMFError, match="no such file"):
        read_capture(tmp_path / "nothing")
    (tmp_path / "x.sigmf-meta").write_text("{not json")
    (tmp_path / "x.sigmf-data").write_bytes(b"")
    with pytest.raises(SigMFError, match="not valid JSON"):
        read_capture(tmp_path / "x")


def test_grid_captures_are_not_iq(tmp_path):
    sim = Simulator.from_scene(builtin_scene("single-plate"), CaptureMode.GRID)
    cap = sim.simulate_pose(0, np.random.default_rng(0))
    with pytest.raises(SigMFError, match="waveform"):
        write_capture(cap, tmp_path / "g")


@given(st.lists(st.tuples(st.floats(-50, 50), st.floats(-50, 50), st.floats(-np.pi + 1e-6, np.pi)),
                min_size=1, max_size=20))
@settings(max_examples=30, deadline=None)
def test_tum_round_trip_and_evo_reads_the_same(tmp_path_factory, rows):
    poses = np.array(rows)
    path = tmp_path_factory.mktemp("tum") / "t.tum"
    write_tum(path, np.arange(len(poses)) * 0.5, poses)
    t, back = read_tum(path)
    assert np.allclose(t, np.arange(len(poses)) * 0.5)
    assert np.allclose(back[:, :2], poses[:, :2], atol=1e-9)
    assert np.allclose(np.angle(np.exp(1j * (back[:, 2] - poses[:, 2]))), 0, atol=1e-8)
    traj = file_interface.read_tum_trajectory_file(str(path))
    assert np.allclose(traj.positions_xyz[:, :2], poses[:, :2], atol=1e-9)
    yaw = np.array([np.arctan2(2 * q[0] * q[3], 1 - 2 * q[3] ** 2) for q in traj.orientations_quat_wxyz])
    assert np.allclose(np.angle(np.exp(1j * (yaw - poses[:, 2]))), 0, atol=1e-8)


def test_bad_tum(tmp_path):
    path = tmp_path / "bad.tum"
    path.write_text("0 1 2 3\n")
    with pytest.raises(TumError) as info:
        read_tum(path)
    assert info.value.field == "line 1"
    path.write_text("0 nan 0 0 0 0 0 1\n")
    with pytest.raises(TumError, match="NaN"):
        read_tum(path)


def test_corrupted_data_fails_the_checksum(written):
    data = data_path(str(written)[: -len(".sigmf-meta")])
    raw = bytearray(data.read_bytes())
    raw[1000] ^= 0xFF
    data.write_bytes(bytes(raw))
    with pytest.raises(SigMFError, match="rejected by sigmf"):
        read_capture(written)


def test_recordings_without_the_radio_block_use_the_named_global_fields(capture, written):
    _edit_meta(written, lambda m: m["global"].pop("radioslam:radio"))
    back = read_capture(written)
    assert back.radio.carrier_hz == 28e9 and back.radio.codebook_bits == 6 and back.radio.array_elements == 8
    assert np.array_equal(back.samples, capture.samples)
