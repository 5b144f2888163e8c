"""simulate → calibrate → sense on the command line, the scan formats, and bad input (exit 2, one line)."""

import json
import subprocess
import sys

import numpy as np
import pytest

from radioslam.io import read_calibration, read_capture, read_scan, write_calibration, write_scan
from radioslam.io.errors import CalibrationFileError, PlyError
from radioslam.sensing import Calibration, CalibrationTarget, Receiver, Scan


def run(*args):
    return subprocess.run([sys.executable, "-m", "radioslam.cli", *args], capture_output=True, text=True, timeout=300)


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    d = tmp_path_factory.mktemp("run") / "plate"
    out = run("simulate", "single-plate:4.8", "--out", str(d), "--save-iq", "--seed", "2")
    assert out.returncode == 0, out.stderr
    return d


def test_simulate_writes_a_calibration_and_sense_writes_scans(run_dir):
    cal = read_calibration(run_dir / "calibration.json")
    assert abs(cal.hardware_delay_s - 32e-6) < 1e-9 and len(cal.targets) == 16
    out = run("sense", str(run_dir))
    assert out.returncode == 0, out.stderr
    scan = read_scan(run_dir / "scans" / "0000.ply")
    facing = np.abs(scan.angle_rad) < 0.1
    assert facing.any() and np.allclose(scan.range_m[facing], 4.8, atol=0.01)
    assert (run_dir / "scans" / "0000.png").stat().st_size > 1000  # Fig. 4(b)/(c)


def test_sense_point_filter_paper_rule_keeps_a_subset_and_a_bad_value_exits_2(run_dir):
    clouds = {}
    for rule in ("scan-peak", "same-range"):
        out = run("sense", str(run_dir), "--point-filter", rule, "--plot-pose", "-1")
        assert out.returncode == 0, out.stderr
        scan = read_scan(run_dir / "scans" / "0000.ply")
        clouds[rule] = set(zip(scan.beam.tolist(), scan.orientation.tolist(), np.round(scan.range_m, 6).tolist()))
    assert clouds["scan-peak"] and clouds["scan-peak"] <= clouds["same-range"]
    out = run("sense", str(run_dir), "--point-filter", "peak")
    assert out.returncode == 2 and "--point-filter" in out.stderr and len(out.stderr.strip().splitlines()) == 1


def test_sense_refinement_from_the_command_line_or_the_config_file(run_dir, tmp_path):
    """--refine paper-bisection, or refine: paper-bisection in the config file's sensing: section, senses
    with the paper's bisection (the plate ranged alike, to millimetres); the flag overrides the file;
    a bad value on either is one line and exit status 2, naming the flag or the dotted field."""
    ranges = {}
    config = tmp_path / "paper.yaml"
    config.write_text("sensing:\n  refine: paper-bisection\n")
    for label, args in {"bracketed": (), "flag": ("--refine", "paper-bisection"), "file": ("--config", str(config)),
                        "override": ("--config", str(config), "--refine", "bracketed")}.items():
        out = run("sense", str(run_dir), "--plot-pose", "-1", *args)
        assert out.returncode == 0, out.stderr
        scan = read_scan(run_dir / "scans" / "0000.ply")
        ranges[label] = scan.range_m[np.argmin(np.abs(scan.angle_rad))]
    assert abs(ranges["flag"] - 4.8) < 0.01 and ranges["flag"] == ranges["file"]
    assert ranges["override"] == ranges["bracketed"] and abs(ranges["bracketed"] - ranges["flag"]) < 2e-3
    out = run("sense", str(run_dir), "--refine", "golden")
    assert out.returncode == 2 and "--refine" in out.stderr and len(out.stderr.strip().splitlines()) == 1
    bad = tmp_path / "bad.yaml"
    bad.write_text("sensing:\n  refine: golden\n")
    out = run("sense", str(run_dir), "--config", str(bad))
    assert out.returncode == 2 and "bad.yaml" in out.stderr and "sensing.refine" in out.stderr
    assert len(out.stderr.strip().splitlines()) == 1


def test_sensing_a_recording_read_back_gives_the_same_scan(run_dir):
    """A test at a bound: the SigMF file path and the in-memory path give identical scans."""
    from radioslam.scene import load_scene
    from radioslam.sim import Simulator

    scene = load_scene(str(run_dir / "scene.yaml"))
    memory = Simulator.from_scene(scene).simulate_pose(0, np.random.default_rng(np.random.SeedSequence(2).spawn(1)[0]))
    disk = read_capture(run_dir / "captures" / "0000")
    assert np.array_equal(memory.samples, disk.samples)
    rx = Receiver(scene.radio, 32e-6)
    a, b = rx.sense(memory).scan, rx.sense(disk).scan
    for field in ("range_m", "angle_rad", "power_db", "beam", "orientation"):
        assert np.array_equal(getattr(a, field), getattr(b, field))


def test_calibrate_from_recorded_captures(tmp_path):
    base = tmp_path / "targets"
    for k, r in enumerate((1.6, 3.2, 6.4)):
        out = run("simulate", f"single-plate:{r}", "--out", str(base / str(k)), "--save-iq", "--seed", str(k))
        assert out.returncode == 0
        (base / "captures").mkdir(parents=True, exist_ok=True)
        for suffix in ("sigmf-meta", "sigmf-data"):
            (base / str(k) / "captures" / f"0000.{suffix}").rename(base / "captures" / f"{k:04d}.{suffix}")
    out = run("calibrate", "--out", str(tmp_path / "cal.json"), "--captures", str(base / "captures"),
              "--ranges", "1.6,3.2,6.4")
    assert out.returncode == 0, out.stderr
    assert abs(read_calibration(tmp_path / "cal.json").hardware_delay_s - 32e-6) < 1e-9
    assert read_calibration(tmp_path / "cal.json").leakage is None
    # with a recorded sweep of every beam with nothing in range, the leakage of each beam too
    from radioslam.config import RadioConfig
    from radioslam.io import write_capture
    from radioslam.sim.calibration_targets import simulate_empty_capture

    write_capture(simulate_empty_capture(RadioConfig(), np.random.default_rng(9)), tmp_path / "empty")
    out = run("calibrate", "--out", str(tmp_path / "cal.json"), "--captures", str(base / "captures"),
              "--ranges", "1.6,3.2,6.4", "--empty", str(tmp_path / "empty"))
    assert out.returncode == 0, out.stderr
    leakage = read_calibration(tmp_path / "cal.json").leakage
    assert len(leakage.delay_s) == 188 and "leakage of 188 beams" in out.stderr
    assert np.median(np.abs(leakage.delay_s - 0.05 / 299_792_458.0)) * 122.88e6 < 0.01  # b/c after T_H
    bad = run("calibrate", "--out", str(tmp_path / "c2.json"), "--captures", str(base / "captures"), "--ranges", "1,2")
    assert bad.returncode == 2 and "--ranges" in bad.stderr and len(bad.stderr.strip().splitlines()) == 1


def test_calibrate_simulated_writes_targets(tmp_path):
    out = run("calibrate", "--out", str(tmp_path / "c.json"), "--targets", "4", "--spacing", "1.5")
    assert out.returncode == 0, out.stderr
    doc = json.loads((tmp_path / "c.json").read_text())
    assert [t["range_m"] for t in doc["targets"]] == [1.5, 3.0, 4.5, 6.0]


def test_sense_without_calibration_says_to_calibrate(run_dir, tmp_path):
    out = run("sense", str(run_dir), "--calibration", str(tmp_path / "none.json"))
    assert out.returncode == 2 and "calibrate" in out.stderr and len(out.stderr.strip().splitlines()) == 1


def _copy_run(run_dir, tmp_path):
    """The run's files as a recorder would leave them: no run.json (a run of ours refuses a damaged file as
    changed since it was written, before any reader sees it; these tests are about the readers)."""
    import shutil

    d = tmp_path / "copy"
    shutil.copytree(run_dir, d)
    (d / "run.json").unlink()
    return d


@pytest.mark.parametrize("damage, fragment", [
    ("truncate", "truncated"),
    ("nan", "NaN"),
    ("annotations", "annotations"),
    ("rate", "sample_rate"),
])
def test_bad_recordings_exit_2_with_one_line(run_dir, tmp_path, damage, fragment):
    d = _copy_run(run_dir, tmp_path)
    meta_file, data_file = d / "captures" / "0000.sigmf-meta", d / "captures" / "0000.sigmf-data"
    meta = json.loads(meta_file.read_text())
    if damage == "truncate":
        data_file.write_bytes(data_file.read_bytes()[:-800])
    elif damage == "nan":
        raw = np.fromfile(data_file, dtype=np.complex64)
        raw[12345] = np.nan
        raw.tofile(data_file)
        meta["global"].pop("core:sha512", None)
    elif damage == "annotations":
        meta["annotations"] = meta["annotations"][:10]
    else:
        meta["global"]["core:sample_rate"] = 61.44e6
    meta_file.write_text(json.dumps(meta))
    out = run("sense", str(d))
    assert out.returncode == 2, out.stderr
    assert fragment in out.stderr and len(out.stderr.strip().splitlines()) == 1 and "Traceback" not in out.stderr
    assert not (d / "scans" / "0000.ply").exists() or (run_dir / "scans").exists()


def test_ply_and_calibration_round_trips(tmp_path):
    scan = Scan(np.array([1.5, 7.25]), np.array([0.3, -2.0]), np.array([0.0, -7.5]), np.array([4, -23]),
                np.array([0, 3]))
    write_scan(tmp_path / "s.ply", scan)
    back = read_scan(tmp_path / "s.ply")
    assert np.allclose(back.range_m, scan.range_m) and np.allclose(back.angle_rad, scan.angle_rad)
    assert np.allclose(back.power_db, scan.power_db) and np.array_equal(back.beam, scan.beam)
    assert np.array_equal(back.orientation, scan.orientation)
    write_scan(tmp_path / "empty.ply", Scan.empty())
    assert len(read_scan(tmp_path / "empty.ply")) == 0
    cal = Calibration(3.2e-5, [CalibrationTarget(0.8, 3.2e-5, 5e-9, 5.3e-9)], "test")
    write_calibration(tmp_path / "c.json", cal)
    assert read_calibration(tmp_path / "c.json") == cal
    (tmp_path / "bad.json").write_text('{"hardware_delay_s": "soon"}')
    with pytest.raises(CalibrationFileError, match="hardware_delay_s"):
        read_calibration(tmp_path / "bad.json")
    (tmp_path / "bad.ply").write_text("not a ply")
    with pytest.raises(PlyError):
        read_scan(tmp_path / "bad.ply")


def test_reproduce_prints_the_starred_keys(tmp_path):
    out = run("reproduce", "fig8", "--out", str(tmp_path), "--json", "--trials", "5")
    assert out.returncode == 0, out.stderr
    doc = json.loads(out.stdout)
    assert {"detect_rate_pdp", "detect_rate_mf", "snr_db"} <= doc.keys()
    assert (tmp_path / "fig8.png").exists() and (tmp_path / "fig8.csv").exists() and (tmp_path / "fig8.md").exists()
    out = run("reproduce", "fig5", "--out", str(tmp_path), "--json", "--trials", "2")
    doc = json.loads(out.stdout)
    assert "snr_db" in doc and all({"peak_sidelobe_db", "mean_sidelobe_db"} <= doc[m].keys()
                                   for m in ("single", "identical", "different"))
    bad = run("reproduce", "fig99", "--out", str(tmp_path))
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1
