"""A battery of bad inputs (issue #15): each case builds a damaged file, directory or command line and
runs the command a user would, under a memory cap and a time limit. One line per case:
- ``ok``: a clean exit 2 with one line on stderr, or a correct success where one is expected;
- ``TRACEBACK``, ``HANG`` (time limit), ``MEMORY`` (the cap hit), ``ACCEPTED`` (exit 0 where bad input
  should be refused), ``LINES`` (exit 2 but not one line), ``FAILED`` (a refusal where success is expected).

    python benchmarks/bad_inputs.py [--work DIR] [--only SUBSTRING] [--memory-gb 3] [--timeout 120]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

ROOM = """version: 1
name: room
walls:
  - {points: [[-4, -3], [4, -3], [4, 3], [-4, 3], [-4, -3]], material: concrete}
trajectory:
  poses: [[-1, 0, 0], [1, 0, 0]]
"""


XML_ROOM = """version: 1
name: room-xml
mitsuba: room.xml
trajectory:
  poses: [[0, 0, 0]]
"""


@dataclass
class Case:
    name: str
    setup: Callable[[Path], list[str]]  # builds its inputs in a fresh directory; the command's arguments
    reject: bool = True  # bad input: exit 2 with one line; False: must succeed
    file_size_limit: int | None = None  # RLIMIT_FSIZE in bytes: a disk that fills mid-write
    env: dict[str, str] | None = None  # added to the environment


def _edit_json(path: Path, change) -> None:
    doc = json.loads(path.read_text())
    change(doc)
    path.write_text(json.dumps(doc))


def _scene(d: Path, text: str) -> Path:
    path = d / "scene.yaml"
    path.write_text(text)
    return path


def _config(d: Path, text: str) -> Path:
    (d / "config.yaml").write_text(text)
    return d / "config.yaml"


def _radio(field: str) -> Callable[[Path], list[str]]:
    return lambda d: ["simulate", str(_scene(d, ROOM + f"radio: {{{field}}}\n")), "--out", str(d / "o")]


def _recording(base: Path, change=None, data=None) -> Callable[[Path], list[str]]:
    """A copy of the one-pose recording with its metadata (or data) damaged; then ``sense``."""

    def setup(d: Path) -> list[str]:
        shutil.copytree(base, d / "r")
        (d / "r" / "run.json").unlink()  # a recorder's directory: the readers meet the damage
        meta, raw = d / "r/captures/0000.sigmf-meta", d / "r/captures/0000.sigmf-data"
        if change is not None:
            meta.write_text(change(meta.read_text()))
        if data is not None:
            data(raw)
        return ["sense", str(d / "r")]

    return setup


def _meta(change) -> Callable[[str], str]:
    def edit(text: str) -> str:
        doc = json.loads(text)
        out = change(doc)
        return json.dumps(doc if out is None else out)

    return edit


def _short_window(text: str) -> str:
    """Every beam window 10 samples long, annotations and data alike (no checksum): consistent, too short."""
    doc = json.loads(text)
    doc["global"]["radioslam:window_samples"] = 10
    doc["global"].pop("core:sha512", None)
    for b, ann in enumerate(doc["annotations"]):
        ann["core:sample_start"], ann["core:sample_count"] = 10 * b, 10
    return json.dumps(doc)


def _short_data(raw: Path) -> None:
    raw.write_bytes(raw.read_bytes()[: 188 * 10 * 8])


def _nan_sample(raw: Path) -> None:
    import numpy as np

    samples = np.fromfile(raw, dtype=np.complex64)
    samples[1234] = np.nan
    samples.tofile(raw)


def _scans(run: Path, damage) -> Callable[[Path], list[str]]:
    """A copy of a two-pose run with scans/0001.ply (or slam.json, calibration.json) damaged, then the stage."""

    def setup(d: Path) -> list[str]:
        shutil.copytree(run, d / "r")
        (d / "r" / "run.json").unlink()
        return damage(d / "r")

    return setup


def _ply_nan(field: str):
    def damage(r: Path) -> list[str]:
        from plyfile import PlyData

        ply = PlyData.read(str(r / "scans/0001.ply"), mmap=False)  # not mapped: it is written over
        ply["vertex"].data[field][0] = float("nan")
        ply.write(str(r / "scans/0001.ply"))
        return ["slam", str(r)]

    return damage


def _file(relative: str, text: str, stage: str):
    def damage(r: Path) -> list[str]:
        (r / relative).write_text(text)
        return [stage, str(r)]

    return damage


def cases(one_pose: Path, two_pose: Path) -> list[Case]:
    deep_json = "[" * 100_000 + "]" * 100_000
    return [
        # scene files
        Case("scene: a FIFO", lambda d: (os.mkfifo(d / "s.yaml"), ["simulate", str(d / "s.yaml"), "--out",
                                                                   str(d / "o")])[1]),
        Case("scene: missing file", lambda d: ["simulate", str(d / "none.yaml"), "--out", str(d / "o")]),
        Case("scene: a directory", lambda d: ["simulate", str(d), "--out", str(d / "o")]),
        Case("scene: /dev/zero", lambda d: ["simulate", "/dev/zero", "--out", str(d / "o")]),
        Case("scene: binary", lambda d: ["simulate", str(_scene(d, "\x00\x01\x02")), "--out", str(d / "o")]),
        Case("scene: duplicate key", lambda d: ["simulate", str(_scene(d, ROOM + "name: again\n")), "--out",
                                                str(d / "o")]),
        Case("scene: nested 1e5 deep", lambda d: ["simulate", str(_scene(d, "a: " + deep_json)), "--out",
                                                  str(d / "o")]),
        Case("scene: 5000-digit number", lambda d: ["simulate", str(_scene(d, ROOM + "radio: {snr_db: " + "9" * 5000
                                                                          + "}\n")), "--out", str(d / "o")]),
        Case("scene: python tag", lambda d: ["simulate", str(_scene(d, "a: !!python/object/apply:os.system [ls]\n")),
                                             "--out", str(d / "o")]),
        Case("scene: alias bomb", lambda d: ["simulate", str(_scene(d, "a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
            f"{chr(98 + i)}: &{chr(98 + i)} [*{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}]\n"
            for i in range(12)))), "--out", str(d / "o")]),
        Case("good: a 10,001-point polyline", lambda d: ["run", str(_scene(d, ROOM.replace(
            "[[-4, -3], [4, -3], [4, 3], [-4, 3], [-4, -3]]", "[" + ", ".join(
                f"[{-4 + 8 * i / 10000:.5f}, -3]" for i in range(10001)) + ", [4, 3], [-4, 3], [-4, -3]]"))),
            "--out", str(d / "o")], reject=False),
        Case("mitsuba: missing file", lambda d: ["simulate", str(_scene(d, XML_ROOM)), "--out", str(d / "o")]),
        Case("mitsuba: not XML", lambda d: ((d / "room.xml").write_text("<scene"),
                                            ["simulate", str(_scene(d, XML_ROOM)), "--out", str(d / "o")])[1]),
        Case("mitsuba: a mesh file missing", lambda d: ((d / "room.xml").write_text(
            '<scene><bsdf type="twosided" id="mat-itu_concrete"/><shape type="ply" id="w"><string name="filename" '
            'value="none.ply"/><ref id="mat-itu_concrete"/></shape></scene>'),
            ["simulate", str(_scene(d, XML_ROOM)), "--out", str(d / "o")])[1]),
        Case("cli: --channel sionna, walls without a height", lambda d: ["simulate", str(_scene(d, ROOM)), "--out",
                                                                         str(d / "o"), "--channel", "sionna"]),
        Case("cli: --channel warp", lambda d: ["simulate", str(_scene(d, ROOM)), "--out", str(d / "o"),
                                               "--channel", "warp"]),
        Case("radio: fft_size 2^24", _radio("fft_size: 16777216")),
        Case("radio: frames 10000", _radio("frames: 10000")),
        Case("radio: array_elements 1e6", _radio("array_elements: 1000000")),
        Case("radio: ray_spacing_deg 1e-7", _radio("ray_spacing_deg: 1.0e-7")),
        Case("radio: elevation_beams even", _radio("elevation_beams: 4")),
        Case("radio: elevation beams off the visible region", _radio("elevation_beams: 15")),
        Case("mitsuba scene with elevation beams on the built-in caster", lambda d: [
            "simulate", str(Path(__file__).resolve().parents[1] / "examples" / "furnished-room" / "room.yaml"),
            "--out", str(d / "o")]),
        # command lines
        Case("cli: --snr-db 1e9", lambda d: ["simulate", str(_scene(d, ROOM)), "--out", str(d / "o"),
                                             "--snr-db", "1e9"]),
        Case("cli: --snr-db -1e9", lambda d: ["simulate", str(_scene(d, ROOM)), "--out", str(d / "o"),
                                              "--snr-db", "-1e9"]),
        Case("cli: --out ''", lambda d: ["simulate", str(_scene(d, ROOM)), "--out", ""]),
        Case("cli: --seed -1", lambda d: ["simulate", str(_scene(d, ROOM)), "--out", str(d / "o"), "--seed", "-1"]),
        Case("cli: calibrate --targets 100000", lambda d: ["calibrate", "--out", str(d / "c.json"), "--targets",
                                                           "100000"]),
        Case("cli: a file name with markup", lambda d: ["simulate", str(d / ":thumbs_up:[b]x.yaml"), "--out",
                                                        str(d / "o")]),
        # --config files, report and export (issue #17)
        Case("config: an unknown section", lambda d: ["run", str(_scene(d, ROOM)), "--out", str(d / "o"), "--config",
                                                      str(_config(d, "radar: {gain: 3}\n"))]),
        Case("config: NaN in radio:", lambda d: ["run", str(_scene(d, ROOM)), "--out", str(d / "o"), "--config",
                                                 str(_config(d, "radio: {snr_db: .nan}\n"))]),
        Case("config: a list", lambda d: ["simulate", str(_scene(d, ROOM)), "--out", str(d / "o"), "--config",
                                          str(_config(d, "- 1\n- 2\n"))]),
        Case("config: missing file", lambda d: ["slam", str(d), "--config", str(d / "none.yaml")]),
        Case("report: an empty directory", lambda d: ["report", str(d)]),
        Case("export: before slam", lambda d: ["export", str(d), "--mcap", str(d / "x.mcap")]),
        Case("export: scans damaged", _scans(two_pose, lambda r: (_ply_nan("power_db")(r),
                                                                  ["export", str(r), "--mcap", str(r / "b.mcap")])[1])),
        # SigMF recordings
        Case("sigmf: meta is an array", _recording(one_pose, _meta(lambda m: [m]))),
        Case("sigmf: annotations: 5", _recording(one_pose, _meta(lambda m: m.update(annotations=5)))),
        Case("sigmf: sample_rate a string", _recording(one_pose, _meta(
            lambda m: m["global"].update({"core:sample_rate": "fast"})))),
        Case("sigmf: sample_rate NaN", _recording(one_pose, lambda t: t.replace(
            '"core:sample_rate": 122880000.0', '"core:sample_rate": NaN'))),
        Case("sigmf: pose_index -1", _recording(one_pose, _meta(
            lambda m: m["global"].update({"radioslam:pose_index": -1})))),
        Case("sigmf: pose_index 1.7", _recording(one_pose, _meta(
            lambda m: m["global"].update({"radioslam:pose_index": 1.7})))),
        Case("sigmf: beam_angle_rad NaN", _recording(one_pose, lambda t: t.replace(
            '"radioslam:beam_angle_rad": ', '"radioslam:beam_angle_rad": NaN, "x": ', 1))),
        Case("sigmf: tx_bits too short", _recording(one_pose, _meta(
            lambda m: m["annotations"][0].update({"radioslam:tx_bits": "AAAA"})))),
        Case("sigmf: short consistent window", _recording(one_pose, _short_window, _short_data)),
        Case("sigmf: duplicate key", _recording(one_pose, lambda t: t.replace('{"global": {', '{"global": {"a": 1, '
                                                                             '"a": 2, ', 1))),
        Case("sigmf: truncated data", _recording(one_pose, data=lambda raw: raw.write_bytes(raw.read_bytes()[:-800]))),
        Case("sigmf: NaN sample", _recording(one_pose, data=_nan_sample)),
        Case("sigmf: two recordings of one pose", lambda d: (
            shutil.copytree(one_pose, d / "r"), (d / "r/run.json").unlink(),
            shutil.copy(d / "r/captures/0000.sigmf-meta", d / "r/captures/0001.sigmf-meta"),
            shutil.copy(d / "r/captures/0000.sigmf-data", d / "r/captures/0001.sigmf-data"),
            ["sense", str(d / "r")])[-1]),
        # scans, slam.json, calibration.json
        Case("ply: NaN power_db", _scans(two_pose, _ply_nan("power_db"))),
        Case("ply: NaN range_m", _scans(two_pose, _ply_nan("range_m"))),
        Case("ply: truncated", _scans(two_pose, lambda r: ((r / "scans/0001.ply").write_bytes(
            (r / "scans/0001.ply").read_bytes()[:300]), ["slam", str(r)])[1])),
        Case("ply: a pose missing", _scans(two_pose, lambda r: ((r / "scans/0000.ply").unlink(), ["slam", str(r)])[1])),
        Case("slam.json: truncated", _scans(two_pose, _file("slam.json", '{"scan_status": [', "evaluate"))),
        Case("slam.json: wrong shape", _scans(two_pose, _file("slam.json", '{"scan_status": 5}', "evaluate"))),
        Case("slam.json: an array", _scans(two_pose, _file("slam.json", "[]", "evaluate"))),
        Case("calibration.json: NaN", lambda d: (shutil.copytree(one_pose, d / "r"), (d / "r/run.json").unlink(),
                                                 (d / "r/calibration.json").write_text('{"hardware_delay_s": NaN}'),
                                                 ["sense", str(d / "r")])[-1]),
        Case("calibration.json: nested 1e5 deep", lambda d: (
            shutil.copytree(one_pose, d / "r"), (d / "r/run.json").unlink(),
            (d / "r/calibration.json").write_text(deep_json), ["sense", str(d / "r")])[-1]),
        # run directories
        Case("run: into a directory of other files", lambda d: ((d / "o").mkdir(), (d / "o/thesis.tex").write_text(
            "x"), ["simulate", str(_scene(d, ROOM)), "--out", str(d / "o")])[-1]),
        Case("run: slam after a failed sense", lambda d: (
            shutil.copytree(one_pose, d / "r"), _edit_json(d / "r/run.json", lambda m: m["stages"].update(
                sense={"status": "failed", "started": "t", "error": "boom"})), ["slam", str(d / "r")])[-1]),
        Case("run: a scan edited after sense", _edit_after_sense(two_pose)),
        Case("run: captures/ a link out of the run", lambda d: (
            (d / "elsewhere").mkdir(), (d / "o").mkdir(), (d / "o/captures").symlink_to(d / "elsewhere"),
            ["simulate", "single-plate:3", "--out", str(d / "o"), "--save-iq", "--force"])[-1]),
        Case("run: the disk fills while writing a capture", lambda d: [
            "simulate", "single-plate:3", "--out", str(d / "o"), "--save-iq"], file_size_limit=1_000_000),
        Case("sweep: an unreachable --scheduler", lambda d: (
            (d / "sweep.yaml").write_text("scenes: [single-plate:3]\nseeds: [1]\n"),
            ["sweep", str(d / "sweep.yaml"), "--out", str(d / "S"), "--scheduler", "tcp://127.0.0.1:9"])[-1],
            env={"DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT": "1s"}),
        Case("good: run the room", lambda d: ["run", str(_scene(d, ROOM)), "--out", str(d / "o")], reject=False),
        Case("good: a second run into the same directory", lambda d: (
            shutil.copytree(two_pose, d / "r"),
            ["run", str(_scene(d, ROOM)), "--out", str(d / "r"), "--seed", "5"])[-1], reject=False),
        Case("good: sense a recorder's directory", lambda d: (
            shutil.copytree(one_pose, d / "r"), (d / "r/run.json").unlink(), ["sense", str(d / "r")])[-1],
            reject=False),
    ]


def _edit_after_sense(run: Path) -> Callable[[Path], list[str]]:
    def setup(d: Path) -> list[str]:
        shutil.copytree(run, d / "r")
        with open(d / "r/scans/0001.ply", "ab") as f:
            f.write(b"\0")
        return ["slam", str(d / "r")]

    return setup


def run_case(case: Case, work: Path, memory_gb: float, timeout: float) -> str:
    d = Path(tempfile.mkdtemp(dir=work))
    args = case.setup(d)

    def cap() -> None:
        limit = int(memory_gb * 2**30)
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
        if case.file_size_limit is not None:
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # the write fails with EFBIG instead
            resource.setrlimit(resource.RLIMIT_FSIZE, (case.file_size_limit, case.file_size_limit))

    tick = time.monotonic()
    proc = subprocess.Popen([sys.executable, "-m", "radioslam.cli", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, preexec_fn=cap, cwd=d, start_new_session=True,
                            env={**os.environ, **(case.env or {})})
    try:
        _, stderr = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.communicate()
        return f"HANG     {case.name} (> {timeout:.0f} s)"
    seconds = time.monotonic() - tick
    lines = stderr.strip().splitlines()
    first = lines[0][:140] if lines else ""
    if "Traceback" in stderr:
        verdict = "MEMORY" if "MemoryError" in stderr else "TRACEBACK"
        return f"{verdict:8} {case.name}: {lines[-1][:140]}"
    if proc.returncode in (-9, 137) or "memory" in first.lower() and proc.returncode not in (0, 2):
        return f"MEMORY   {case.name} (exit {proc.returncode})"
    if case.reject:
        if proc.returncode == 0:
            return f"ACCEPTED {case.name} ({seconds:.1f} s)"
        if proc.returncode != 2 or len(lines) != 1:
            return f"LINES    {case.name}: exit {proc.returncode}, {len(lines)} lines: {first}"
        return f"ok       {case.name}: {first}"
    if proc.returncode != 0:
        return f"FAILED   {case.name}: exit {proc.returncode}: {first}"
    return f"ok       {case.name}: success in {seconds:.1f} s"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--work", type=Path, default=None)
    ap.add_argument("--only", default="")
    ap.add_argument("--memory-gb", type=float, default=3.0)
    ap.add_argument("--timeout", type=float, default=120.0)
    args = ap.parse_args()
    work = args.work or Path(tempfile.mkdtemp(prefix="radioslam-bad-"))
    work.mkdir(parents=True, exist_ok=True)
    one_pose, two_pose = work / "one-pose", work / "two-pose"
    if not one_pose.exists():
        subprocess.run([sys.executable, "-m", "radioslam.cli", "simulate", "single-plate:3", "--out", str(one_pose),
                        "--save-iq"], check=True, capture_output=True)
    if not two_pose.exists():
        (work / "room.yaml").write_text(ROOM)
        subprocess.run([sys.executable, "-m", "radioslam.cli", "run", str(work / "room.yaml"), "--out",
                        str(two_pose)], check=True, capture_output=True)
    results = []
    for case in cases(one_pose, two_pose):
        if args.only in case.name:
            results.append(run_case(case, work, args.memory_gb, args.timeout))
            print(results[-1], flush=True)
    verdicts = [r.split()[0] for r in results]
    print(f"{len(results)} cases: {verdicts.count('ok')} ok, " + ", ".join(
        f"{verdicts.count(v)} {v.lower()}" for v in ("TRACEBACK", "HANG", "MEMORY", "ACCEPTED", "LINES", "FAILED")))


if __name__ == "__main__":
    main()
