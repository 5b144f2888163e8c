"""run.json (issue #15): a run directory never mixes two runs, stages refuse incomplete or foreign
inputs with one line, and only files a manifest lists are ever removed."""

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from radioslam.io.errors import ManifestError
from radioslam.io.manifest import RunManifest, StageStatus, file_hash

FOUR_POSES = """version: 1
name: four
walls:
  - {points: [[-4, -3], [4, -3], [4, 3], [-4, 3], [-4, -3]], material: concrete}
trajectory:
  poses: [[-1.5, 0, 0], [-0.5, 0, 0], [0.5, 0, 0], [1.5, 0, 0]]
"""


def cli(*args, **kwargs):
    return subprocess.run([sys.executable, "-m", "radioslam.cli", *map(str, args)], capture_output=True, text=True,
                          timeout=300, **kwargs)


def one_line(out) -> str:
    assert out.returncode == 2, out.stderr
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in out.stderr, out.stderr
    return lines[0]


def _write(root, relative, text="x"):
    path = root / relative
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def _stage(manifest, stage, *files):
    with manifest.stage(stage):
        for f in files:
            _write(manifest.root, f, f"{stage} {f}")


def test_a_complete_stage_lists_its_files_with_their_hashes_and_the_next_one_checks_them(tmp_path):
    m = RunManifest(tmp_path / "run")
    m.new_run(seed=3, scene="paper-cnv")
    _stage(m, "simulate", "scene.yaml", "ground_truth.tum", "calibration.json")
    _stage(m, "sense", "scans/0000.ply", "scans/0001.ply")
    doc = json.loads((m.root / "run.json").read_text())
    assert doc["seed"] == 3 and doc["scene"] == "paper-cnv" and doc["versions"]["radioslam"]
    sense = doc["stages"]["sense"]
    assert sense["status"] == "complete" and sorted(sense["outputs"]) == ["scans/0000.ply", "scans/0001.ply"]
    assert sense["outputs"]["scans/0001.ply"] == file_hash(m.root / "scans/0001.ply")
    m.begin("slam")  # inputs as listed: accepted

    for damage, fragment in [(lambda: _write(m.root, "scans/0001.ply", "edited"), "changed since 'sense' wrote it"),
                             (lambda: (m.root / "scans/0001.ply").unlink(), "missing"),
                             (lambda: _write(m.root, "scans/0002.ply"), "not part of this run")]:
        _stage(m, "sense", "scans/0000.ply", "scans/0001.ply")
        damage()
        with pytest.raises(ManifestError, match=fragment):
            m.begin("slam")
        (m.root / "scans/0002.ply").unlink(missing_ok=True)


@pytest.mark.parametrize("how", ["failed", "killed"])
def test_a_stage_that_did_not_finish_blocks_every_later_one(tmp_path, how):
    m = RunManifest(tmp_path)
    m.new_run(seed=0, scene="s")
    _stage(m, "simulate", "scene.yaml")
    if how == "failed":
        with pytest.raises(RuntimeError), m.stage("sense"):
            _write(tmp_path, "scans/0000.ply")
            raise RuntimeError("pose 1: bad recording")
    else:  # begun, then nothing: a kill -9
        m.begin("sense")
        _write(tmp_path, "scans/0000.ply")
    for later in ("slam", "evaluate"):
        with pytest.raises(ManifestError) as caught:
            m.begin(later)
        assert caught.value.field == "stages.sense.status"
        assert ("failed (RuntimeError: pose 1: bad recording)" if how == "failed" else "never finished") in \
            caught.value.reason


def test_a_stage_rerun_removes_what_it_and_every_later_stage_wrote_and_nothing_else(tmp_path):
    m = RunManifest(tmp_path)
    m.new_run(seed=0, scene="s")
    _stage(m, "simulate", "scene.yaml", "captures/0000.sigmf-meta", "captures/0000.sigmf-data")
    _stage(m, "sense", "scans/0000.ply", "scans/0001.ply")
    _stage(m, "slam", "trajectory.tum", "slam.json")
    _stage(m, "evaluate", "metrics.json")
    mine = _write(tmp_path, "scans/notes.txt", "mine")
    _write(tmp_path, "scans/.0000.ply.abcd1234.tmp")  # a killed writer's
    m.begin("sense")
    assert not any((tmp_path / f).exists() for f in ("scans/0000.ply", "scans/0001.ply", "trajectory.tum",
                                                      "slam.json", "metrics.json", "scans/.0000.ply.abcd1234.tmp"))
    assert mine.read_text() == "mine" and (tmp_path / "captures/0000.sigmf-data").exists()
    assert set(m.load().stages) == {"simulate", "sense"}


def test_a_new_run_replaces_the_old_one_whole_and_refuses_a_directory_not_a_run(tmp_path):
    m = RunManifest(tmp_path / "run")
    m.new_run(seed=1, scene="s")
    _stage(m, "simulate", "scene.yaml", "odometry.tum")
    _stage(m, "sense", *(f"scans/{k:04d}.ply" for k in range(4)))
    first = m.load().run_id
    m.new_run(seed=2, scene="s")
    assert m.load().run_id != first and m.load().stages == {}
    assert not (m.root / "scans/0003.ply").exists() and not (m.root / "odometry.tum").exists()

    other = tmp_path / "theirs"
    _write(other, "thesis.tex", "mine")
    with pytest.raises(ManifestError, match="no run.json: not a radioslam run") as caught:
        RunManifest(other).new_run(seed=0, scene="s")
    assert caught.value.field == "(directory)" and not (other / "run.json").exists()
    RunManifest(other).new_run(seed=0, scene="s", force=True)
    assert (other / "thesis.tex").read_text() == "mine"


def test_files_are_never_removed_through_a_link_out_of_the_run(tmp_path):
    outside = tmp_path / "elsewhere"
    _write(outside, "0000.sigmf-meta", "precious")
    root = tmp_path / "run"
    m = RunManifest(root)
    m.new_run(seed=0, scene="s")
    _stage(m, "simulate", "captures/0000.sigmf-meta")
    (root / "captures" / "0000.sigmf-meta").unlink()
    (root / "captures").rmdir()
    (root / "captures").symlink_to(outside)  # replaced by a link after the run wrote its file there
    m.new_run(seed=1, scene="s")
    assert (outside / "0000.sigmf-meta").read_text() == "precious"


@pytest.mark.parametrize("stage, folder", [("simulate", "captures"), ("sense", "scans")])
def test_a_stage_never_writes_through_a_link_out_of_the_run(tmp_path, stage, folder):
    outside = tmp_path / "elsewhere"
    outside.mkdir()
    root = tmp_path / "run"
    m = RunManifest(root)
    m.new_run(seed=0, scene="s")
    if stage == "sense":
        _stage(m, "simulate", "scene.yaml")
    (root / folder).symlink_to(outside)
    with pytest.raises(ManifestError, match="a symbolic link .*never through a link") as caught:
        m.begin(stage)
    assert caught.value.file == str(root / folder) and caught.value.field == "(directory)"
    assert not list(outside.iterdir())


def test_simulate_into_a_run_whose_captures_are_a_link_is_one_line_and_writes_nothing_there(tmp_path):
    outside = tmp_path / "elsewhere"
    outside.mkdir()
    out = tmp_path / "R"
    out.mkdir()
    (out / "captures").symlink_to(outside)
    done = cli("simulate", "single-plate:3", "--out", out, "--save-iq", "--force")
    assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
    assert f"{out / 'captures'}: (directory): a symbolic link" in done.stderr
    assert not list(outside.iterdir())


def test_a_replacement_killed_between_its_manifest_and_the_removals_is_finished_by_the_next_run(tmp_path):
    m = RunManifest(tmp_path)
    m.new_run(seed=0, scene="s")
    _stage(m, "sense", "scans/0000.ply")
    manifest = m.load()
    manifest.removing, manifest.stages = ["scans/0000.ply"], {}  # the new manifest saved, then the kill
    m.save(manifest)
    m.new_run(seed=1, scene="s")
    assert not (tmp_path / "scans/0000.ply").exists() and m.load().removing == []


def test_a_directory_without_a_manifest_is_adopted_as_found(tmp_path):
    _write(tmp_path, "scans/0000.ply")
    _write(tmp_path, "scans/0001.ply")
    RunManifest(tmp_path).begin("slam")
    sense = RunManifest(tmp_path).load().stages["sense"]
    assert sense.source.value == "found" and sense.status is StageStatus.COMPLETE and len(sense.outputs) == 2


def test_a_malformed_manifest_is_one_line_naming_the_field(tmp_path):
    (tmp_path / "run.json").write_text(json.dumps({"run_id": 5}))
    with pytest.raises(ManifestError) as caught:
        RunManifest(tmp_path).begin("slam")
    assert caught.value.file.endswith("run.json") and caught.value.field


# the mixed runs, through the command line

@pytest.fixture(scope="module")
def scene_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("scene") / "four.yaml"
    path.write_text(FOUR_POSES)
    return path


def test_a_run_killed_while_replacing_another_is_refused_by_slam_and_evaluate(scene_file, tmp_path):
    out = tmp_path / "R"
    assert cli("run", scene_file, "--out", out, "--seed", "1").returncode == 0
    assert json.loads((out / "run.json").read_text())["stages"]["report"]["status"] == "complete"
    second = subprocess.Popen([sys.executable, "-m", "radioslam.cli", "run", str(scene_file), "--out", str(out),
                               "--seed", "2"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    def sensing_seed_2() -> bool:  # the new run's second scan written (the old run's went first)
        try:
            doc = json.loads((out / "run.json").read_text())
        except (OSError, ValueError):
            return False
        return doc["seed"] == 2 and "sense" in doc["stages"] and (out / "scans/0001.ply").exists()

    deadline = time.monotonic() + 120
    while not sensing_seed_2() and time.monotonic() < deadline and second.poll() is None:
        time.sleep(0.005)
    second.send_signal(signal.SIGKILL)
    second.wait()
    doc = json.loads((out / "run.json").read_text())
    assert doc["seed"] == 2 and doc["stages"].get("sense", {}).get("status") != "complete"
    assert not (out / "scans/0003.ply").exists()  # the seed-1 scans went with the seed-1 run
    assert "stages.sense.status" in one_line(cli("slam", out))
    line = one_line(cli("evaluate", out))
    assert "stages.sense.status" in line or "stages.slam" in line or "not written by this run" in line


def test_a_sense_that_failed_halfway_is_refused_by_slam(scene_file, tmp_path):
    out = tmp_path / "R"
    assert cli("simulate", scene_file, "--out", out, "--save-iq").returncode == 0
    (out / "run.json").unlink()  # a recorder's directory: the damage is met by the reader, at pose 2
    data = out / "captures/0002.sigmf-data"
    data.write_bytes(data.read_bytes()[:-800])
    assert "truncated" in one_line(cli("sense", out))
    assert (out / "scans/0001.ply").exists()
    assert "stage 'sense' failed" in one_line(cli("slam", out))


def test_a_smaller_run_into_a_bigger_ones_directory_leaves_none_of_its_scans(scene_file, tmp_path):
    out = tmp_path / "R"
    assert cli("run", scene_file, "--out", out).returncode == 0
    two = tmp_path / "two.yaml"
    two.write_text(FOUR_POSES.replace(", [0.5, 0, 0], [1.5, 0, 0]", ""))
    assert cli("run", two, "--out", out, "--json").returncode == 0
    assert sorted(p.name for p in (out / "scans").glob("*.ply")) == ["0000.ply", "0001.ply"]
    assert json.loads((out / "metrics.json").read_text())["poses"] == 2
    assert cli("slam", out).returncode == 0  # a stage rerun on a complete run: fine


def test_an_empty_out_path_and_a_foreign_directory_are_refused(scene_file, tmp_path):
    assert "--out" in (line := one_line(cli("simulate", scene_file, "--out", ""))) and "empty path" in line
    _write(tmp_path / "mine", "thesis.tex")
    line = one_line(cli("run", scene_file, "--out", tmp_path / "mine"))
    assert "not a radioslam run" in line and "--force" in line
    assert cli("simulate", scene_file, "--out", tmp_path / "mine", "--force").returncode == 0
    assert (tmp_path / "mine/thesis.tex").exists() and (tmp_path / "mine/run.json").exists()
    assert os.listdir(tmp_path / "mine")


def test_poses_past_9999_are_named_kept_and_read_in_pose_order(tmp_path, monkeypatch):
    """The schema accepts 100,000 poses: pose 10,000's files are ``10000.*``, belong to their stage, and
    are read after 9999 (a four-digit pattern dropped them; a name sort put 10000 before 2)."""
    from radioslam.io.manifest import stage_of
    from radioslam.io.rundir import RunDir
    from radioslam.pipeline import slam as pipeline

    run = RunDir(tmp_path)
    assert run.scan_file(10_000).name == "10000.ply" and run.scan_file(7).name == "0007.ply"
    assert run.capture_base(10_000).name == "10000"
    assert stage_of("scans/10000.ply") == "sense" and stage_of("captures/10000.sigmf-data") == "simulate"
    assert stage_of("scans/123.ply") is None  # fewer than four digits: not a run's file
    run.scans.mkdir()
    for k in range(10_001):
        run.scan_file(k).touch()
    monkeypatch.setattr(pipeline, "read_scan", lambda path: int(path.stem))
    assert pipeline.read_scans(run) == list(range(10_001))
    run.scan_file(9_999).unlink()
    with pytest.raises(pipeline.RadioslamError, match="missing scan of a pose"):
        pipeline.read_scans(run)


def test_each_stage_records_the_files_it_read_with_the_hashes_they_had(tmp_path):
    """run.json's stages.NAME.inputs: the earlier stages' files the stage reads, by relative path, and
    a file it was given from outside (slam --odometry) by absolute path, each with its SHA-256 as it
    was when the stage began; simulate's input, the scene, is its settings' scene_sha256."""
    run = tmp_path / "R"
    for stage, paths in {"simulate": ["scene.yaml", "ground_truth.tum", "calibration.json",
                                      "captures/0000.sigmf-meta", "captures/0000.sigmf-data"],
                         "sense": ["scans/0000.ply", "scans/0000.png"]}.items():
        manifest = RunManifest(run)
        if stage == "simulate":
            manifest.new_run(1, "room")
        with manifest.stage(stage, {"k": stage}):
            for p in paths:
                (run / p).parent.mkdir(parents=True, exist_ok=True)
                (run / p).write_text(f"{stage} {p}")
    odometry = tmp_path / "wheels.tum"
    odometry.write_text("0 0 0 0 0 0 0 1\n")
    with RunManifest(run).stage("slam", {}, external=[odometry, tmp_path / "missing.tum"]):
        pass
    stages = json.loads((run / "run.json").read_text())["stages"]
    assert stages["simulate"]["inputs"] == {}
    assert stages["sense"]["inputs"] == {p: file_hash(run / p) for p in
                                         ["calibration.json", "captures/0000.sigmf-data", "captures/0000.sigmf-meta",
                                          "ground_truth.tum", "scene.yaml"]}
    # not the figure, nor the missing file
    assert stages["slam"]["inputs"] == {"scans/0000.ply": file_hash(run / "scans/0000.ply"),
                                        "ground_truth.tum": file_hash(run / "ground_truth.tum"),  # --scene-frame
                                        str(odometry.resolve()): file_hash(odometry)}


@pytest.mark.parametrize("argv, recorded", [
    (["/venv/bin/radioslam", "run", "paper-cnv"], ["radioslam", "run", "paper-cnv"]),
    (["/src/radioslam/cli/__main__.py", "demo"], ["radioslam", "demo"]),
    (["-c"], ["python", "-c", "…"]),
    (["study.py", "--n", "3"], ["python", "study.py", "--n", "3"]),
])
def test_the_command_recorded_is_how_the_run_was_started(monkeypatch, argv, recorded):
    from radioslam.io.manifest import invocation

    monkeypatch.setattr(sys, "argv", argv)
    assert invocation() == recorded
