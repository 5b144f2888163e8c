"""The command line's manners (issue #17): -h and --help everywhere, -q and -v, choices, one seed default,
whole summaries, --config on every stage, 'report DIR', and progress off a terminal."""

import json
import os
import re
import subprocess
import sys

import pytest
import yaml
from cli_process import cli

COMMANDS = ("simulate", "calibrate", "sense", "slam", "evaluate", "report", "scenes", "run", "demo", "reproduce",
            "sweep", "export")
ROOM = {"version": 1, "name": "small-room",
        "walls": [{"points": [[-4, -3], [5, -3], [5, 3], [-4, 3], [-4, -3]], "material": "concrete"},
                  {"points": [[1.5, 0.5], [2.5, 0.5], [2.5, 1.5], [1.5, 1.5], [1.5, 0.5]], "material": "metal"}],
        "trajectory": {"circle": {"center": [0.0, 0.0], "radius": 1.0, "poses": 6}}}




@pytest.fixture
def room(tmp_path):
    path = tmp_path / "room.yaml"
    path.write_text(yaml.safe_dump(ROOM))
    return path


def test_h_is_help_and_the_summaries_are_whole():
    out = cli("-h")
    assert out.returncode == 0 and not out.stderr
    listing = " ".join(out.stdout.split())
    for command in COMMANDS:
        assert f" {command} " in listing
    # the summary goes on past its first period (click cut it there: "demo  The paper's Fig.")
    assert "Fig. 6 simulation end to end: paper-cnv, 60 poses" in listing


def test_every_command_has_h_help_quiet_verbose_and_one_seed():
    from typer.testing import CliRunner

    from radioslam.cli import app

    runner = CliRunner()
    for command in COMMANDS:  # in this process: the help of every command, without twelve start-ups
        short, long = runner.invoke(app, [command, "-h"]), runner.invoke(app, [command, "--help"])
        assert short.exit_code == 0 and short.output == long.output and "Usage: " in short.output, command
        text = " ".join(short.output.split())
        assert "-q, --quiet" in text and "-v, --verbose" in text, command
        if "--seed" in text:  # every command that draws has the same default, and says what it seeds
            assert "seed of every random draw" in text and "[default: 0; x>=0]" in text, command


@pytest.mark.parametrize("args, fragment", [
    (("sense", ".", "--detector", "dual"), "'single', 'multi'"),
    (("run", "paper-cnv", "--out", "x", "--point-filter", "nearest"), "'scan-peak', 'same-range'"),
    (("reproduce", "fig9", "--out", "x"), "'table1', 'fig5', 'fig8', 'fig6', 'impairments', 'all'"),
    (("reproduce", "table1", "--out", "x", "--impairments", "rust"), "'ideal', 'iq', 'adc'"),
    (("run", "paper-cnv", "--out", "x", "--refine", "newton"), "'bracketed', 'paper-bisection'"),
])
def test_fixed_sets_of_values_are_choices(args, fragment):
    out = cli(*args)
    assert out.returncode == 2 and out.stderr.count("\n") == 1 and fragment in out.stderr


def test_impairment_choices_are_the_profiles():
    from radioslam.choices import ImpairmentProfile
    from radioslam.eval.experiments.impairments import PROFILES

    assert [p.value for p in ImpairmentProfile] == list(PROFILES)


def test_quiet_says_nothing_verbose_says_more(room, tmp_path):
    quiet = cli("simulate", room, "--out", tmp_path / "q", "-q")
    assert quiet.returncode == 0 and quiet.stderr == ""
    top = cli("-q", "simulate", room, "--out", tmp_path / "q2")
    assert top.returncode == 0 and top.stderr == ""
    normal = cli("simulate", room, "--out", tmp_path / "n")
    assert normal.returncode == 0 and normal.stderr.startswith("wrote ") and normal.stderr.count("\n") == 1
    verbose = cli("simulate", room, "--out", tmp_path / "v", "-v")
    assert "radioslam: simulate: " in verbose.stderr and "seed 0" in verbose.stderr
    bad = cli("simulate", tmp_path / "none.yaml", "--out", tmp_path / "b", "-q")  # errors still speak
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1


def test_progress_off_a_terminal_is_a_line_every_interval(room, tmp_path):
    out = cli("run", room, "--out", tmp_path / "r", env={"RADIOSLAM_PROGRESS_INTERVAL": "0"})
    assert out.returncode == 0, out.stderr
    lines = [line for line in out.stderr.splitlines() if line.startswith("radioslam: simulating and sensing: ")]
    assert len(lines) >= 5 and "/6 (" in lines[0] and "/s, ETA " in lines[0]
    assert lines[-1].startswith("radioslam: simulating and sensing: 6/6 in ")
    assert "radioslam: SLAM: 6/6 in " in out.stderr  # every stage speaks, SLAM too
    quiet = cli("run", room, "--out", tmp_path / "q", "-q", env={"RADIOSLAM_PROGRESS_INTERVAL": "0"})
    assert quiet.returncode == 0 and "simulating" not in quiet.stderr
    slow = cli("reproduce", "fig8", "--out", tmp_path / "f", "--trials", "3", env={"RADIOSLAM_PROGRESS_INTERVAL": "0"})
    assert slow.returncode == 0 and "radioslam: Fig. 8: two targets: " in slow.stderr


def test_progress_on_a_terminal_is_a_bar_that_goes_away(room, tmp_path):
    """stderr a pseudo-terminal: rich's bar counts the poses up to 6/6, then is erased; no progress lines."""
    import pty

    leader, follower = pty.openpty()
    child = subprocess.Popen([sys.executable, "-m", "radioslam.cli", "run", str(room), "--out", str(tmp_path / "r")],
                             stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=follower,
                             env={**os.environ, "TERM": "xterm-256color", "COLUMNS": "100",
                                  "RADIOSLAM_PROGRESS_INTERVAL": "0"})
    os.close(follower)
    chunks = []
    while True:
        try:
            chunk = os.read(leader, 65536)
        except OSError:  # the child closed the terminal
            break
        if not chunk:
            break
        chunks.append(chunk)
    os.close(leader)
    assert child.wait(timeout=300) == 0
    shown = b"".join(chunks).decode(errors="replace")
    counts = {"simulating and sensing": [], "SLAM": []}
    for stage, done in re.findall(r"\x1b\[2K(simulating and sensing|SLAM) .*?(\d+)/6", shown):
        counts[stage].append(int(done))
    # the refresh thread draws what it finds (a stage may end between two frames); the last stage's last
    # frame is drawn as the bar stops
    assert counts["simulating and sensing"][0] < 6 and counts["SLAM"][-1] == 6 and "━" in shown
    assert all(sorted(seen) == seen for seen in counts.values())
    assert "\x1b[1A\x1b[2K" in shown  # transient: the bar's line is cleared before 'wrote'
    assert "radioslam: simulating and sensing:" not in shown and "radioslam: SLAM:" not in shown and "wrote " in shown


def test_config_sections_reach_their_stages(room, tmp_path):
    config = tmp_path / "config.yaml"
    config.write_text(yaml.safe_dump({"radio": {"snr_db": 5.0}, "sensing": {"detector": "multi"},
                                      "slam": {"scan": {"max_points": 500}}}))
    out = cli("run", room, "--out", tmp_path / "r", "--config", config, "--json")
    assert out.returncode == 0, out.stderr
    manifest = json.loads((tmp_path / "r/run.json").read_text())
    stages = manifest["stages"]
    assert stages["simulate"]["settings"]["radio"]["snr_db"] == 5.0
    assert stages["sense"]["settings"]["sensing"]["detector"] == "multi"
    assert stages["slam"]["settings"]["slam"]["scan"]["max_points"] == 500
    # the command line wins over the file
    over = cli("run", room, "--out", tmp_path / "o", "--config", config, "--snr-db", "12", "--detector", "single")
    assert over.returncode == 0, over.stderr
    stages = json.loads((tmp_path / "o/run.json").read_text())["stages"]
    assert stages["simulate"]["settings"]["radio"]["snr_db"] == 12.0
    assert stages["sense"]["settings"]["sensing"]["detector"] == "single"


BAD_CONFIGS = [("radar: {}\n", "radar: unknown section"), ("radio: {snr: 3}\n", "radio.snr: Extra inputs"),
               ("sensing: {detector: dual}\n", "sensing.detector: Input should be"), ("slam: 3\n", "slam")]


@pytest.mark.parametrize("command, bad", [(c, 0) for c in ("simulate", "sense", "slam", "run", "demo")]
                         + [("run", k) for k in (1, 2, 3)])
def test_a_bad_config_is_one_line_naming_the_field(tmp_path, room, command, bad):
    """Every command that takes --config refuses a bad one in one line; each kind of bad field is named."""
    text, field = BAD_CONFIGS[bad]
    config = tmp_path / "bad.yaml"
    config.write_text(text)
    target = {"simulate": [room, "--out", tmp_path / "o"], "run": [room, "--out", tmp_path / "o"],
              "demo": ["--out", tmp_path / "o"], "sense": [tmp_path], "slam": [tmp_path]}[command]
    out = cli(command, *target, "--config", config)
    assert out.returncode == 2 and out.stderr.count("\n") == 1
    assert f"{config}: {field}" in out.stderr
    assert not (tmp_path / "o").exists()  # refused before anything was written


@pytest.fixture(scope="module")
def staged(tmp_path_factory):
    """The stages one by one on the small room (seed 2, a config's sensing: section), then its report."""
    base = tmp_path_factory.mktemp("staged")
    room, config, run_dir = base / "room.yaml", base / "config.yaml", base / "r"
    room.write_text(yaml.safe_dump(ROOM))
    config.write_text(yaml.safe_dump({"sensing": {"point_filter": "scan-peak"}}))
    outs = [cli(*args) for args in (("simulate", room, "--out", run_dir, "--save-iq", "--config", config, "--seed", 2),
                                    ("sense", run_dir, "--config", config, "--plot-pose", "2"),
                                    ("slam", run_dir, "--config", config), ("evaluate", run_dir), ("report", run_dir))]
    return room, config, run_dir, outs


def test_stages_one_by_one_then_report(staged):
    """The stages one by one, each with --config where it takes one, then 'radioslam report DIR'."""
    _, _, run_dir, outs = staged
    assert [out.returncode for out in outs] == [0] * 5, [out.stderr for out in outs]
    assert (run_dir / "report.html").stat().st_size > 10_000 and (run_dir / "scans/0002.png").is_file()
    assert outs[-1].stderr.strip() == f"wrote {run_dir / 'report.html'}"
    stages = json.loads((run_dir / "run.json").read_text())["stages"]
    assert stages["report"]["status"] == "complete"
    assert stages["sense"]["settings"]["sensing"]["point_filter"] == "scan-peak"
    assert "ATE RMSE, SLAM" in outs[3].stdout and " cm" in outs[3].stdout  # names and units


def test_run_save_iq_is_the_stages_one_by_one(staged, tmp_path):
    """run --save-iq writes the captures and senses them from the files: the scans the stages made."""
    room, config, run_dir, _ = staged
    out = cli("run", room, "--out", tmp_path / "a", "--save-iq", "--seed", "2", "--config", config)
    assert out.returncode == 0, out.stderr
    assert len(list((tmp_path / "a/captures").glob("*.sigmf-data"))) == 6
    for k in range(6):
        assert (tmp_path / f"a/scans/{k:04d}.ply").read_bytes() == (run_dir / f"scans/{k:04d}.ply").read_bytes()
