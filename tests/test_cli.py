"""The command line ★: outputs of simulate, and exit status 2 with one line on bad input."""

import numpy as np
import pytest
from cli_process import cli as run

from radioslam.io import read_capture, read_tum
from radioslam.scene import load_scene


def test_version():
    from radioslam import __version__

    out = run("--version")
    assert out.returncode == 0 and out.stdout.strip() == f"radioslam {__version__}"


def test_no_command_prints_help():
    out = run()
    assert out.returncode == 0 and "simulate" in out.stdout and not out.stderr


def test_scenes_lists_the_builtins():
    out = run("scenes")
    assert out.returncode == 0
    for name in ("paper-cnv", "glass-door", "single-plate"):
        assert name in out.stdout


def test_simulate_writes_the_run_directory(tmp_path):
    out = run("simulate", "single-plate:3.2", "--out", str(tmp_path / "run"), "--seed", "4", "--save-iq",
              "--snr-db", "15")
    assert out.returncode == 0, out.stderr
    run_dir = tmp_path / "run"
    scene = load_scene(run_dir / "scene.yaml")
    assert scene.radio.snr_db == 15.0 and scene.radio.hardware_delay_s == 32e-6  # defaults filled in
    t, poses = read_tum(run_dir / "ground_truth.tum")
    assert np.allclose(poses, [[0, 0, 0]])
    cap = read_capture(run_dir / "captures" / "0000.sigmf-meta")
    assert cap.samples.shape[0] == 188
    again = run("simulate", "single-plate:3.2", "--out", str(tmp_path / "run2"), "--seed", "4", "--save-iq",
                "--snr-db", "15")
    assert again.returncode == 0
    first, second = run_dir / "captures/0000.sigmf-data", tmp_path / "run2/captures/0000.sigmf-data"
    assert first.read_bytes() == second.read_bytes()
    # a rerun into the same directory removes the earlier run's recordings (run.json lists them) and
    # nothing else: a file run.json does not list is never removed, and a stage refuses to read it
    (run_dir / "captures/0007.sigmf-meta").write_text("{}")
    (run_dir / "captures/notes.txt").write_text("mine")
    assert run("simulate", "single-plate:3.2", "--out", str(run_dir)).returncode == 0
    assert sorted(p.name for p in (run_dir / "captures").iterdir()) == ["0007.sigmf-meta", "notes.txt"]
    refused = run("sense", str(run_dir))
    assert refused.returncode == 2 and refused.stderr.count("\n") == 1
    assert "captures/0007.sigmf-meta: (file): not part of this run" in refused.stderr


SCENE = """version: 1
name: t
walls:
  - {points: [[-5, -5], [5, -5], [5, 5], [-5, 5], [-5, -5]], material: concrete}
trajectory:
  poses: [[0, 0, 0]]
"""


@pytest.mark.parametrize("text, fragment", [
    (SCENE + "colour: red\n", "colour: unknown key"),
    (SCENE.replace("walls:\n  - {points: [[-5, -5], [5, -5], [5, 5], [-5, 5], [-5, -5]], material: concrete}\n",
                   ""), "walls: required key is missing"),
    (SCENE.replace("[[-5, -5], [5, -5], [5, 5], [-5, 5], [-5, -5]]", "[[1, 1]]"),
     "walls[0].points: a polyline needs at least 2 points"),
    (SCENE.replace("concrete", "cheese"), "walls[0].material: unknown material 'cheese'"),
    (SCENE.replace("[[0, 0, 0]]", "[[4.9, 0, 0]]"), "trajectory.poses[0]: pose 0 at (4.900, 0.000) is 0.100 m"),
    ("walls: [{points: [[0, 0], [1, 0]]\n", "line 2: not valid YAML"),
    ("\x00\x01binary", "not valid YAML"),
])
def test_bad_scene_exits_2_with_one_line(tmp_path, text, fragment):
    path = tmp_path / "scene.yaml"
    path.write_text(text)
    out = run("simulate", str(path), "--out", str(tmp_path / "o"))
    assert out.returncode == 2
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in out.stderr
    assert lines[0].startswith(f"radioslam: error: {path}: ") and fragment in lines[0]
    assert not (tmp_path / "o" / "scene.yaml").exists()


def test_missing_scene_file_exits_2(tmp_path):
    out = run("simulate", str(tmp_path / "none.yaml"), "--out", str(tmp_path / "o"))
    assert out.returncode == 2 and out.stderr.strip().endswith("(file): no such file")
    assert len(out.stderr.strip().splitlines()) == 1


def test_unwritable_output_exits_2(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    out = run("simulate", "single-plate", "--out", str(blocker / "sub"))
    assert out.returncode == 2 and len(out.stderr.strip().splitlines()) == 1


def _readme_block(marker: str) -> str:
    from pathlib import Path

    text = (Path(__file__).parent.parent / "README.md").read_text()
    after = text.split(f"<!-- {marker} -->", 1)[1]
    return after.split("```", 2)[1].strip()


def test_readme_commands_use_real_options():
    main = _readme_block("main-command")
    assert "pip install ." in main and "radioslam demo" in main
    help_text = run("demo", "--help").stdout
    for option in [w for w in main.split() if w.startswith("--")]:
        assert option in help_text
    assert "pytest" in _readme_block("test-command")


@pytest.mark.parametrize("args, fragment", [
    (["simulate", "single-plate", "--out", "OUT", "--snr-db", "nan"], "radio.snr_db: Input should be a finite number"),
    (["simulate", "single-plate", "--out", "OUT", "--seed", "-1"], "'--seed'"),
    (["simulate", "--bogus"], "--bogus"),
    (["simulate", "single-plate"], "Missing option '--out'"),
    (["teleport"], "No such command 'teleport'"),
])
def test_usage_errors_exit_2_with_one_line(tmp_path, args, fragment):
    out = run(*[str(tmp_path / "o") if a == "OUT" else a for a in args])
    assert out.returncode == 2
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("radioslam: error: ") and fragment in lines[0]
    assert not (tmp_path / "o").exists()


def test_nan_coordinate_is_rejected(tmp_path):
    path = tmp_path / "scene.yaml"
    path.write_text(SCENE.replace("[-5, -5], [5, -5]", "[-5, .nan], [5, -5]"))
    out = run("simulate", str(path), "--out", str(tmp_path / "o"))
    assert out.returncode == 2 and "walls[0].points[0][1]: Input should be a finite number" in out.stderr
