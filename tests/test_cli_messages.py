"""The command line's one line (issue #15 point 5): user strings are never markup, lines never wrap off
a terminal, warnings are counted, and SIGINT/SIGTERM end in one line, exit 130/143 and no temporary file."""

import json
import signal
import subprocess
import sys
import time

import pytest


def cli(*args, **kwargs):
    return subprocess.run([sys.executable, "-m", "radioslam.cli", *map(str, args)], capture_output=True, text=True,
                          timeout=300, **kwargs)


@pytest.mark.parametrize("name", [":thumbs_up:.yaml", "radioslam:radio:[bold]x[/bold].yaml",
                                  "a-very-long-name-" + "x" * 150 + ".yaml"])
def test_a_file_name_is_printed_as_it_is_on_one_line(tmp_path, name):
    out = cli("simulate", tmp_path / name, "--out", tmp_path / "o")
    assert out.returncode == 2
    assert out.stderr.count("\n") == 1 and f"{tmp_path / name}: (file): no such file" in out.stderr


@pytest.mark.parametrize("sig, code, word", [(signal.SIGTERM, 143, "terminated"), (signal.SIGINT, 130, "interrupted")])
def test_a_signal_ends_a_run_in_one_line_leaving_no_temporary_file_and_the_stage_failed(tmp_path, sig, code, word):
    out = tmp_path / "R"
    # SIGINT as a terminal would deliver it: a shell starting this test in the background ignores it (and
    # the child would inherit that), so the child gets the default disposition back
    proc = subprocess.Popen([sys.executable, "-m", "radioslam.cli", "demo", "--out", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))

    def sensing() -> bool:
        try:
            return json.loads((out / "run.json").read_text())["stages"]["sense"]["status"] == "started"
        except (OSError, ValueError, KeyError):
            return False

    deadline = time.monotonic() + 120
    while not sensing() and time.monotonic() < deadline:
        time.sleep(0.01)
    time.sleep(0.3)  # into the scans
    proc.send_signal(sig)
    _, stderr = proc.communicate(timeout=60)
    assert proc.returncode == code
    assert stderr.count("\n") == 1 and f"radioslam: {word}" in stderr, stderr
    assert not list(out.rglob("*.tmp"))
    sense = json.loads((out / "run.json").read_text())["stages"]["sense"]
    assert sense["status"] == "failed"
    assert "radioslam: error: " in cli("slam", out).stderr  # and the next stage refuses it
