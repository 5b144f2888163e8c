"""Kills (issue #15 points 1 and 2): `run --resume` after a kill goes on from the last recorded pose and
ends byte-identical to a clean run; a run killed at any moment leaves a directory that is either complete
and consistent, or that every next stage reports incomplete."""

import json
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from radioslam.errors import RadioslamError
from radioslam.pipeline import evaluate_stage, slam_stage

SCENE = """version: 1
name: resume
walls:
  - {points: [[-4, -3], [4, -3], [4, 3], [-4, 3], [-4, -3]], material: concrete}
  - {points: [[0, 1], [1, 1.5]], material: metal}
trajectory:
  poses: [[-1.5, 0, 0], [-0.8, -0.2, 0.1], [0, 0, 0.2], [0.8, 0.2, 0.3], [1.5, 0, 0.3]]
"""
# what differs between two runs of the same command: clocks
TIMING_KEYS = {"timings_s", "ms_per_scan", "slam_ms_per_scan_median", "slam_ms_per_scan", "ms"}
DETERMINISTIC = ["scene.yaml", "ground_truth.tum", "calibration.json", "trajectory.tum", "trajectory_odometry.tum",
                 "map.pgm", "map.yaml", "map.ply"]


def cli(*args):
    return subprocess.run([sys.executable, "-m", "radioslam.cli", *map(str, args)], capture_output=True, text=True,
                          timeout=300)


def _manifest(out):
    try:
        return json.loads((out / "run.json").read_text())
    except (OSError, ValueError):
        return None


def _killed_at(args, out, moment, deadline_s=120.0):
    """Start ``radioslam *args``, SIGKILL it once ``moment(run.json)`` holds; False if it finished first."""
    proc = subprocess.Popen([sys.executable, "-m", "radioslam.cli", *map(str, args)], stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + deadline_s
    while proc.poll() is None and time.monotonic() < deadline:
        doc = _manifest(out)
        if doc is not None and moment(doc):
            proc.send_signal(signal.SIGKILL)
            proc.wait()
            return True
        time.sleep(0.005)
    proc.wait()
    return False


def _same_outputs(a, b):
    for name in DETERMINISTIC + sorted(p.relative_to(a).as_posix() for p in (a / "scans").glob("*.ply")):
        assert (a / name).read_bytes() == (b / name).read_bytes(), name
    for name in ("slam.json", "metrics.json"):
        first, second = (_untimed(json.loads((d / name).read_text())) for d in (a, b))
        assert first == second, name


def _untimed(doc):
    if isinstance(doc, dict):
        return {k: _untimed(v) for k, v in doc.items() if k not in TIMING_KEYS}
    return [_untimed(v) for v in doc] if isinstance(doc, list) else doc


@pytest.fixture(scope="module")
def scene_and_clean(tmp_path_factory):
    root = tmp_path_factory.mktemp("resume")
    scene = root / "scene.yaml"
    scene.write_text(SCENE)
    tick = time.monotonic()
    assert cli("run", scene, "--out", root / "clean", "--seed", "3").returncode == 0
    return scene, root / "clean", time.monotonic() - tick


def _scans_recorded(n):
    return lambda doc: len(doc["stages"].get("sense", {}).get("outputs", {})) >= n


@pytest.mark.parametrize("moment", [
    pytest.param(lambda doc: doc["stages"].get("simulate", {}).get("status") == "complete", id="after-simulate"),
    pytest.param(_scans_recorded(2), id="two-scans-in"),
    pytest.param(lambda doc: "slam" in doc["stages"], id="during-slam"),
])
def test_a_killed_run_resumed_ends_byte_identical_to_a_clean_one(scene_and_clean, tmp_path, moment):
    scene, clean, _ = scene_and_clean
    out = tmp_path / "R"
    if not _killed_at(["run", scene, "--out", out, "--seed", "3"], out, moment):
        pytest.skip("the run finished before the moment came")
    kept = {f: (out / f).stat().st_mtime_ns for f in _manifest(out)["stages"].get("sense", {}).get("outputs", {})}
    resumed = cli("run", scene, "--out", out, "--seed", "3", "--resume")
    assert resumed.returncode == 0, resumed.stderr
    _same_outputs(clean, out)
    for f, mtime in kept.items():  # what the killed run recorded was not done again
        assert (out / f).stat().st_mtime_ns == mtime, f
    assert all(s["status"] == "complete" for s in _manifest(out)["stages"].values())


def test_resume_refuses_another_scene_or_seed(scene_and_clean, tmp_path):
    scene, clean, _ = scene_and_clean
    out = tmp_path / "R"
    assert _killed_at(["run", scene, "--out", out, "--seed", "3"], out, _scans_recorded(1))
    line = cli("run", scene, "--out", out, "--seed", "4", "--resume").stderr
    assert line.count("\n") == 1 and "--resume: this directory holds a run of" in line and "seed 3" in line


def test_a_run_killed_at_ten_random_moments_is_complete_or_refused_by_every_next_stage(scene_and_clean, tmp_path):
    scene, _, seconds = scene_and_clean
    rng = np.random.default_rng(15)
    for i, delay in enumerate(rng.uniform(0.0, seconds, 10)):
        out = tmp_path / f"R{i}"
        proc = subprocess.Popen([sys.executable, "-m", "radioslam.cli", "run", str(scene), "--out", str(out)],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep(delay)
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        stages = (_manifest(out) or {"stages": {}})["stages"]
        # in this process (the command line turns a RadioslamError into exit 2 and its one line: test_cli)
        for stage, before in ((evaluate_stage, ("simulate", "sense", "slam")), (slam_stage, ("simulate", "sense"))):
            ready = all(stages.get(s, {}).get("status") == "complete" for s in before)
            if ready:  # complete and consistent as far as this stage needs
                stage(out)
            else:  # reported incomplete
                with pytest.raises(RadioslamError) as refused:
                    stage(out)
                assert "\n" not in refused.value.one_line(), (i, delay)
