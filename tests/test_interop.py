"""Files that load anywhere (issue #17): the ROS 2 bag read back and decoded message by message, a PGM reader
that follows the Netpbm format, PLY properties of the types Open3D's tensor reader keeps, the map frame and
the scene frame against evo."""

import collections
import shutil
import subprocess
import sys
import warnings

import numpy as np
import pytest

from radioslam.io import read_scan, read_tum
from radioslam.io.errors import RosMapError
from radioslam.io.ros_map import read_pgm, read_ros_map

OPEN3D_TENSOR_TYPES = {"uchar", "int", "float", "double"}  # Open3D 0.20's t.io PLY reader keeps these only


def _decoded(bag):
    """(topic, log time ns, message) of every message, decoded with the schemas in the file."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    with open(bag, "rb") as stream:
        for _, channel, message, decoded in make_reader(stream, decoder_factories=[DecoderFactory()]) \
                .iter_decoded_messages():
            yield channel.topic, message.log_time, decoded


def test_mcap_round_trip_decodes_every_message(demo_run, tmp_path):
    out, _ = demo_run
    bag = tmp_path / "run.mcap"
    done = subprocess.run([sys.executable, "-m", "radioslam.cli", "export", str(out), "--mcap", str(bag)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    stamps, slam = read_tum(out / "trajectory.tum")
    _, truth = read_tum(out / "ground_truth.tum")
    counts, scans, tf = collections.Counter(), [], []
    for topic, log_time, msg in _decoded(bag):
        counts[topic] += 1
        if topic == "/radioslam/scan":
            assert msg.header.frame_id == "base_link" and msg.is_bigendian is False
            dtype = np.dtype({"names": [f.name for f in msg.fields], "offsets": [f.offset for f in msg.fields],
                              "formats": [{7: "<f4", 5: "<i4", 2: "u1"}[f.datatype] for f in msg.fields],
                              "itemsize": msg.point_step})
            scans.append((log_time, np.frombuffer(bytes(msg.data), dtype=dtype)))
        elif topic == "/tf":
            t = msg.transforms[0]
            assert (t.header.frame_id, t.child_frame_id) == ("map", "base_link")
            tf.append([t.transform.translation.x, t.transform.translation.y,
                       2 * np.arctan2(t.transform.rotation.z, t.transform.rotation.w)])
        elif topic == "/map":
            cells, meta = read_ros_map(out / "map.yaml")
            assert (msg.info.width, msg.info.height) == cells.shape and msg.info.resolution == pytest.approx(
                meta["resolution"])
            data = np.asarray(msg.data, dtype=np.int8).reshape(msg.info.height, msg.info.width).T
            assert np.array_equal(data == 100, cells == 0) and np.array_equal(data == -1, cells == 205)
        elif topic in ("/radioslam/path/slam", "/radioslam/path/ground_truth"):
            poses = np.array([[p.pose.position.x, p.pose.position.y] for p in msg.poses])
            np.testing.assert_allclose(poses, (slam if topic.endswith("slam") else truth)[:, :2], atol=1e-9)
        elif topic == "/tf_static":
            assert msg.transforms[0].child_frame_id == "map"
            assert msg.transforms[0].transform.translation.x == pytest.approx(truth[0, 0])
        elif topic == "/radioslam/loop_closures":
            assert len(msg.markers[0].points) % 2 == 0 and msg.markers[0].type == 5
    assert counts == {"/radioslam/scan": 60, "/tf": 60, "/tf_static": 1, "/map": 1, "/radioslam/path/slam": 1,
                      "/radioslam/path/front_end": 1, "/radioslam/path/ground_truth": 1,
                      "/radioslam/loop_closures": 1}
    np.testing.assert_allclose(np.array(tf), slam, atol=1e-9)
    for k, (log_time, points) in enumerate(scans):  # stamped at the run's pose times, every point kept
        assert log_time == int(round(stamps[k] * 1e9))
        scan = read_scan(out / f"scans/{k:04d}.ply")
        np.testing.assert_allclose(np.column_stack([points["x"], points["y"], points["z"]]), scan.xyz, atol=1e-5)
        np.testing.assert_array_equal(points["beam"], scan.beam)
        np.testing.assert_array_equal(points["orientation"], scan.orientation)


def test_export_needs_a_slammed_run(tmp_path):
    out = subprocess.run([sys.executable, "-m", "radioslam.cli", "export", str(tmp_path), "--mcap",
                          str(tmp_path / "x.mcap")], capture_output=True, text=True, timeout=120)
    assert out.returncode == 2 and out.stderr.count("\n") == 1 and "trajectory.tum" in out.stderr
    assert not (tmp_path / "x.mcap").exists()


IMAGE = np.array([[0, 254, 205, 7], [254, 254, 0, 205], [205, 0, 254, 254]], dtype=np.uint8)


@pytest.mark.parametrize("header", [b"P5\n4 3\n255\n", b"P5 4 3 255 ", b"P5\n# CREATOR: GIMP PNM Filter\n4 3\n255\n",
                                    b"P5\n# one\n# two\n4\t\t3\r\n# three\n255\n", b"P5#c\n4#d\n3\n#e\n255\n"])
def test_pgm_headers_with_any_comments_and_whitespace(header):
    np.testing.assert_array_equal(read_pgm(header + IMAGE.tobytes()), IMAGE)


def test_plain_and_sixteen_bit_pgm():
    plain = b"P2\n# plain\n4 3\n255\n" + b"\n".join(b" ".join(str(v).encode() for v in row) for row in IMAGE)
    np.testing.assert_array_equal(read_pgm(plain), IMAGE)
    wide = IMAGE.astype(np.uint16) * 257
    np.testing.assert_array_equal(read_pgm(b"P5 4 3 65535\n" + wide.astype(">u2").tobytes()), wide)


@pytest.mark.parametrize("data, field", [(b"P6\n4 3\n255\n" + bytes(36), "header"), (b"P5\n4 3\n", "header"),
                                         (b"P5\n4 x\n255\n" + bytes(12), "header"),
                                         (b"P5\n4 3\n255\n" + bytes(11), "data"),
                                         (b"P5\n4 3\n100\n" + bytes([200] * 12), "data")])
def test_bad_pgm_is_one_error_naming_the_part(data, field):
    with pytest.raises(RosMapError) as info:
        read_pgm(data, "m.pgm")
    assert info.value.field == field


def test_a_gimp_style_map_reads_as_written(demo_run, tmp_path):
    out, _ = demo_run
    cells, meta = read_ros_map(out / "map.yaml")
    shutil.copy(out / "map.yaml", tmp_path / "map.yaml")
    rows = cells.T[::-1]
    (tmp_path / "map.pgm").write_bytes(b"P5\n# CREATOR: GIMP\n# another\n%d %d\n255\n" % (rows.shape[1], rows.shape[0])
                                       + rows.tobytes())
    again, _ = read_ros_map(tmp_path / "map.yaml")
    np.testing.assert_array_equal(again, cells)


def test_ply_properties_are_types_open3d_keeps(demo_run):
    out, _ = demo_run
    for path in (out / "scans/0000.ply", out / "map.ply"):
        header = path.read_bytes().split(b"end_header")[0].decode("ascii").splitlines()
        types = {line.split()[1] for line in header if line.startswith("property ")}
        assert types <= OPEN3D_TENSOR_TYPES, (path, types)
        assert {line.split()[2] for line in header if line.startswith("property ")} >= {"beam", "elevation_beam"}


def test_open3d_reads_every_property_without_a_warning(demo_run, tmp_path, capfd):
    """Open3D's C++ logger writes to the process's stdout: captured at the file descriptor. A control file with
    an int16 property (what the PLYs had before) shows that the check sees Open3D's warning."""
    o3d = pytest.importorskip("open3d", reason="Open3D is not installed (pip install open3d-cpu) to read the PLYs with")
    from plyfile import PlyData, PlyElement

    control = np.zeros(3, dtype=[("x", "f4"), ("y", "f4"), ("z", "f4"), ("beam", "i2")])
    PlyData([PlyElement.describe(control, "vertex")]).write(str(tmp_path / "int16.ply"))
    capfd.readouterr()
    o3d.t.io.read_point_cloud(str(tmp_path / "int16.ply"))
    assert "WARNING" in "".join(capfd.readouterr())
    out, _ = demo_run
    for path in (out / "scans/0000.ply", out / "map.ply"):
        cloud = o3d.t.io.read_point_cloud(str(path))
        assert {"positions", "power_db", "beam", "orientation", "range_m", "elevation_beam"} <= set(cloud.point)
        np.testing.assert_array_equal(cloud.point["beam"].numpy().ravel(), read_scan(path).beam)
        assert len(o3d.io.read_point_cloud(str(path)).points) == len(read_scan(path).range_m)
        assert "WARNING" not in "".join(capfd.readouterr()), path


def test_scene_frame_trajectory_needs_no_alignment_in_evo(demo_run, tmp_path):
    """trajectory.tum is in the map frame (the terminal's at the first pose): evo without -a is far off; the
    scene-frame file gives evo's unaligned APE within a few mm of the aligned ATE."""
    from evo.core import metrics
    from evo.tools import file_interface

    from radioslam.pipeline import slam_stage

    out, result = demo_run
    run = tmp_path / "run"
    shutil.copytree(out, run)
    slam_stage(run, scene_frame=True)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # evo reads every file without a warning
        truth = file_interface.read_tum_trajectory_file(str(run / "ground_truth.tum"))
        ape = {}
        for name in ("trajectory.tum", "trajectory_scene.tum"):
            metric = metrics.APE(metrics.PoseRelation.translation_part)
            metric.process_data((truth, file_interface.read_tum_trajectory_file(str(run / name))))
            ape[name] = metric.get_statistic(metrics.StatisticsType.rmse)
    assert ape["trajectory.tum"] > 1.0
    assert ape["trajectory_scene.tum"] < result["ate_rmse_m"] + 0.01
    _, first = read_tum(run / "trajectory_scene.tum")
    _, true = read_tum(run / "ground_truth.tum")
    np.testing.assert_allclose(first[0], true[0], atol=1e-6)  # the map frame is the first true pose
