"""The command line's one line (issue #15 point 5): user strings are never markup, lines never wrap off
a terminal, warnings are counted, and SIGINT/SIGTERM end in one line, exit 130/143 and no temporary file."""

import json
import signal
import subprocess
import time

import pytest
from cli_process import cli, cli_argv


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
    proc = subprocess.Popen(cli_argv("demo", "--out", out,
                                     prelude="import signal; signal.signal(signal.SIGINT, signal.default_int_handler)"),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)

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
    assert proc.returncode == code, stderr
    assert stderr.count("\n") == 1 and f"radioslam: {word}" in stderr, stderr
    assert not list(out.rglob("*.tmp"))
    sense = json.loads((out / "run.json").read_text())["stages"]["sense"]
    assert sense["status"] == "failed"
    assert "radioslam: error: " in cli("slam", out).stderr  # and the next stage refuses it


# in the child: writes past the limit fail with EFBIG (a full disk's stand-in), no SIGXFSZ kill
_FILE_SIZE_LIMIT = ("import resource, signal; signal.signal(signal.SIGXFSZ, signal.SIG_IGN); "
                    "resource.setrlimit(resource.RLIMIT_FSIZE, ({limit}, {limit}))")


def test_a_write_that_fails_names_the_file_being_written_and_leaves_no_half_written_one(tmp_path):
    # numpy's tofile says only "N requested and M written", naming no file: the writer names it
    out = tmp_path / "R"
    done = subprocess.run(cli_argv("simulate", "single-plate:3", "--out", out, "--save-iq",
                                   prelude=_FILE_SIZE_LIMIT.format(limit=1_000_000)),
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 2, done.stderr
    assert done.stderr.count("\n") == 1, done.stderr
    assert f"radioslam: error: {out / 'captures' / '0000.sigmf-data'}: (file): " in done.stderr
    assert "a short write, the disk full or a file-size limit reached" in done.stderr
    assert not list(out.rglob("*.tmp")) and not list((out / "captures").iterdir())
    assert json.loads((out / "run.json").read_text())["stages"]["simulate"]["status"] == "failed"
    refused = cli("sense", out)  # the next stage refuses what is there
    assert refused.returncode == 2 and refused.stderr.count("\n") == 1


def test_an_unreachable_scheduler_is_one_line_naming_its_address(tmp_path):
    sweep = tmp_path / "sweep.yaml"
    sweep.write_text("scenes: [single-plate:3]\nseeds: [1]\n")
    env = {**__import__("os").environ, "DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT": "1s"}
    done = cli("sweep", sweep, "--out", tmp_path / "S", "--scheduler", "tcp://127.0.0.1:9", env=env)
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1, done.stderr
    assert done.stderr.startswith("radioslam: error: tcp://127.0.0.1:9: --scheduler: cannot reach the Dask scheduler")
