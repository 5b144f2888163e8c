"""Fuzzed inputs (issue #15): every draw of a damaged scene YAML, SigMF metadata, calibration JSON, PLY
scan or slam.json either reads or raises the project's one-line error, never anything else (a traceback
on the command line). Each example starts from a valid file and breaks one thing, or is random bytes."""

import copy
import json
import os
import tempfile
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from radioslam.errors import RadioslamError
from radioslam.io import read_calibration, read_capture, read_scan, write_capture, write_scan
from radioslam.io.slam_summary import read_slam_summary
from radioslam.scene import load_scene
from radioslam.scene.loader import load_scene_file
from radioslam.sensing.pointcloud import Scan
from radioslam.sim import Simulator

FUZZ = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])

leaves = (st.none() | st.booleans() | st.integers(-10**6, 10**6) | st.floats(allow_nan=False, allow_infinity=False)
          | st.text(max_size=12))
values = st.recursive(leaves, lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8), inner,
                                                                                           max_size=4), max_leaves=12)

SCENE = {"version": 1, "name": "fuzz",
         "walls": [{"points": [[-4, -3], [4, -3], [4, 3], [-4, 3], [-4, -3]], "material": "concrete"}],
         "trajectory": {"poses": [[0, 0, 0], [1, 0, 0.1]]}, "radio": {"snr_db": 10.0}}


def _paths(doc, prefix=()):
    """Every key path of a nested document (dict keys and list indices)."""
    yield prefix
    children = doc.items() if isinstance(doc, dict) else enumerate(doc) if isinstance(doc, list) else ()
    for key, child in children:
        yield from _paths(child, (*prefix, key))


@st.composite
def damaged(draw, base):
    """``base`` with one key path replaced by a random value, or removed, or with an extra key."""
    doc = copy.deepcopy(base)
    path = draw(st.sampled_from(list(_paths(doc))[1:]))
    parent = doc
    for key in path[:-1]:
        parent = parent[key]
    action = draw(st.sampled_from(["replace", "remove", "extra"]))
    if action == "remove":
        del parent[path[-1]]
    elif action == "extra" and isinstance(parent, dict):
        parent[draw(st.text(min_size=1, max_size=8))] = draw(values)
    else:
        parent[path[-1]] = draw(values)
    return doc


def _reads_or_refuses(read):
    try:
        read()
    except RadioslamError as exc:
        assert "\n" not in exc.one_line() and exc.reason


@FUZZ
@given(doc=damaged(SCENE))
def test_a_damaged_scene_loads_or_is_one_error(doc):
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "scene.yaml"
        path.write_text(yaml.safe_dump(doc))
        _reads_or_refuses(lambda: load_scene_file(path))


@FUZZ
@given(text=st.binary(max_size=200) | st.text(max_size=200).map(str.encode))
def test_random_bytes_as_a_scene_are_one_error(text):
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "scene.yaml"
        path.write_bytes(text)
        _reads_or_refuses(lambda: load_scene_file(path))


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    base = tmp_path_factory.mktemp("rec") / "0000"
    scene = load_scene("single-plate:3")
    write_capture(Simulator.from_scene(scene).simulate_pose(0, np.random.default_rng(0)), base)
    meta = json.loads(Path(f"{base}.sigmf-meta").read_text())
    meta["annotations"] = meta["annotations"][:3] + meta["annotations"][-2:]  # fewer paths to draw from
    return base, meta


@FUZZ
@given(data=st.data())
def test_damaged_sigmf_metadata_reads_or_is_one_error(recording, data):
    base, meta = recording
    full = json.loads(Path(f"{base}.sigmf-meta").read_text())
    doc = data.draw(damaged(meta))
    if isinstance(doc.get("annotations"), list) and len(doc["annotations"]) == 5:  # put the full list back
        doc["annotations"] = doc["annotations"][:3] + full["annotations"][3:-2] + doc["annotations"][-2:]
    with tempfile.TemporaryDirectory() as d:
        copy_base = Path(d) / "0000"
        os.link(f"{base}.sigmf-data", f"{copy_base}.sigmf-data")
        Path(f"{copy_base}.sigmf-meta").write_text(json.dumps(doc))
        _reads_or_refuses(lambda: read_capture(copy_base))


CALIBRATION = {"hardware_delay_s": 3.2e-05, "source": "fuzz",
               "targets": [{"range_m": 0.8, "t1_s": 3.2e-05, "t2_s": 3.2e-05, "ota_s": 5.3e-09}]}


SUMMARY = {"scan_status": ["matched", "matched"], "status_counts": {"matched": 2}, "tracking_lost": False,
           "lost_scans": [], "match_score": [None, 0.5], "ms_per_scan": [1.0, 2.0],
           "loop_closures": [{"anchor": 0, "pose": 1, "score": 0.4, "weight": 1.0}], "points_per_scan": [10, 12],
           "slam_ms_per_scan_median": 1.5, "timings_s": {"slam": 0.1}, "config": {}}


@pytest.mark.parametrize("name, base, read", [("calibration.json", CALIBRATION, read_calibration),
                                              ("slam.json", SUMMARY, read_slam_summary)])
@FUZZ
@given(data=st.data())
def test_a_damaged_json_file_reads_or_is_one_error(name, base, read, data):
    doc = data.draw(damaged(base) | values)
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / name
        path.write_text(json.dumps(doc))
        _reads_or_refuses(lambda: read(path))


@pytest.fixture(scope="module")
def ply_bytes(tmp_path_factory):
    path = tmp_path_factory.mktemp("ply") / "0000.ply"
    n = 20
    write_scan(path, Scan(np.linspace(1, 5, n), np.linspace(-1, 1, n), np.zeros(n), np.arange(n) - 10,
                          np.zeros(n, np.int64)))
    return path.read_bytes()


@FUZZ
@given(data=st.data())
def test_a_damaged_ply_scan_reads_or_is_one_error(ply_bytes, data):
    raw = bytearray(ply_bytes)
    how = data.draw(st.sampled_from(["truncate", "flip", "header", "value"]))
    if how == "truncate":
        raw = raw[: data.draw(st.integers(0, len(raw) - 1))]
    elif how == "flip":
        for _ in range(data.draw(st.integers(1, 8))):
            raw[data.draw(st.integers(0, len(raw) - 1))] = data.draw(st.integers(0, 255))
    elif how == "header":
        end = raw.index(b"end_header")
        raw[: end] = data.draw(st.binary(max_size=end))
    else:  # a float field of one vertex: NaN, infinite or huge
        start = raw.index(b"end_header\n") + len(b"end_header\n")
        offset = start + data.draw(st.integers(0, 19)) * 35 + data.draw(st.sampled_from([0, 8, 16, 31]))
        raw[offset:offset + 8] = np.array([data.draw(st.sampled_from([np.nan, np.inf, -1e308, 1e300]))]).tobytes()
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "0000.ply"
        path.write_bytes(bytes(raw))
        _reads_or_refuses(lambda: read_scan(path))
