"""``run.json``, the run manifest (issue #15): how a run directory was made, and which files belong to it.

A run directory is written by stages, each reading what the ones before it wrote:
simulate → sense → slam → evaluate → report. The manifest records each stage's status
(started, complete, failed), its settings and the SHA-256 of every file it wrote. That gives
three rules:
- a stage starts only on inputs that one complete run wrote: every stage before it complete,
  and the files on disk exactly the ones listed, with the listed hashes;
- starting a stage invalidates it and every stage after it, and removes their files;
- a new run (``simulate``, ``run``, ``demo``) replaces the old one as a whole.

A directory never mixes two runs. Only files a manifest lists are ever removed, and never
through a symbolic link out of the directory; nor is a stage's file written through one (a
``captures/`` or ``scans/`` that is a link is refused: the run's files stay in the run
directory). A directory without ``run.json`` that holds recordings or scans from elsewhere is
adopted: the files found are recorded as the outputs of the stages that would have written them
(``source: found``). A new run refuses a directory that holds other files, unless forced.
"""

from __future__ import annotations

import hashlib
import json
import os
import platform
import re
import sys
import uuid
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from datetime import datetime, timezone
from enum import Enum
from importlib import metadata
from pathlib import Path

from pydantic import BaseModel, ConfigDict, ValidationError

from radioslam.io.atomic import atomic_write_text
from radioslam.io.errors import ManifestError
from radioslam.io.json_io import dumps, read_json
from radioslam.io.rundir import RunDir

MANIFEST = "run.json"
FORMAT = "radioslam-run/1"
# simulate's files besides its captures
_SIMULATED = (r"scene\.yaml", r"ground_truth\.tum", r"calibration\.json", r"odometry\.tum")
_CAPTURES, _SCANS = r"captures/\d{4,}\.sigmf-(meta|data)", r"scans/\d{4,}\.ply"
# each stage's files, as patterns relative to the run directory, in the order the stages run
STAGE_FILES: dict[str, tuple[str, ...]] = {
    "simulate": (*_SIMULATED, _CAPTURES),
    "sense": (_SCANS, r"scans/\d{4,}\.png"),
    "slam": (r"trajectory\.tum", r"trajectory_odometry\.tum", r"trajectory_scene\.tum", r"trajectory_alternative\.tum",
             r"map\.pgm", r"map\.yaml", r"map\.ply", r"slam\.json"),
    "evaluate": (r"metrics\.json",),
    "report": (r"report\.html", r"fig6\.png", r"scan_status\.png", r"map3d\.png"),
}
STAGES = tuple(STAGE_FILES)
# the files of earlier stages each stage reads: recorded with their hashes as its inputs
STAGE_INPUTS: dict[str, tuple[str, ...]] = {
    "simulate": (),  # the scene as given: its hash is in the settings (scene_sha256)
    "sense": (*_SIMULATED, _CAPTURES),
    "slam": (_SCANS, r"odometry\.tum", r"ground_truth\.tum"),
    "evaluate": (*_SIMULATED, _SCANS, *STAGE_FILES["slam"]),
    "report": (*_SIMULATED, *STAGE_FILES["sense"], *STAGE_FILES["slam"], *STAGE_FILES["evaluate"]),
}
_FOLDERS = ("", "captures", "scans")
_VERSIONED = ("numpy", "scipy", "gtsam", "sigmf", "pydantic", "typer", "rich", "matplotlib", "PyYAML")


class StageStatus(str, Enum):
    STARTED = "started"  # running, or killed while running
    COMPLETE = "complete"
    FAILED = "failed"


class Source(str, Enum):
    RAN = "ran"  # written by this stage of radioslam
    FOUND = "found"  # found in the directory, written elsewhere (a recorder), adopted as they were


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid")


class StageRecord(_Model):
    status: StageStatus
    source: Source = Source.RAN
    started: str
    finished: str | None = None
    settings: dict = {}
    # what it read (STAGE_INPUTS: relative paths of earlier stages' files; other files by absolute
    # path, e.g. slam --odometry) → SHA-256, as verified when it began
    inputs: dict[str, str] = {}
    outputs: dict[str, str] = {}  # relative path → SHA-256
    # files named as this stage's outputs that were there, unlisted, when it began: not its outputs
    # (unless it wrote them again), never removed
    foreign: dict[str, str] = {}
    error: str | None = None


class Manifest(_Model):
    format: str = FORMAT
    run_id: str
    created: str
    command: list[str]
    versions: dict[str, str]
    seed: int | None = None
    scene: str | None = None  # the scene as given (file or built-in name); scene.yaml holds it as run
    stages: dict[str, StageRecord] = {}
    removing: list[str] = []  # files of a replaced run still to remove (a kill between the two steps)


def _now() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="seconds")


def invocation() -> list[str]:
    """What started this run: ``radioslam ARGS`` from the command line (its script or ``python -m``), else the
    Python program with its arguments; ``python -c`` leaves no program to name."""
    program = sys.argv[0] if sys.argv else ""
    if Path(program).name == "radioslam" or Path(program).parts[-3:-1] == ("radioslam", "cli"):
        return ["radioslam", *sys.argv[1:]]
    if program in ("", "-c"):
        return ["python", "-c", "…"]
    return ["python", *sys.argv]


def versions() -> dict[str, str]:
    """radioslam's, Python's and the main dependencies' versions."""
    found = {"radioslam": _version("radioslam"), "python": platform.python_version()}
    return {**found, **{name: _version(name) for name in _VERSIONED}}


def _version(name: str) -> str:
    try:
        return metadata.version(name)
    except metadata.PackageNotFoundError:
        return "absent"


def _as_stored(settings: dict) -> dict:
    """``settings`` as run.json holds them (JSON types), so that a stage's settings compare equal to the
    stored ones."""
    return json.loads(dumps(settings))


def file_hash(path: Path) -> str:
    """SHA-256 of a file, read in blocks of 1 MiB."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(2**20), b""):
            digest.update(block)
    return digest.hexdigest()


def stage_of(relative: str) -> str | None:
    """The stage that writes the file at this relative path, None: not one of a run's files."""
    return next((stage for stage, patterns in STAGE_FILES.items()
                 if any(re.fullmatch(p, relative) for p in patterns)), None)


def run_files(root: Path) -> dict[str, list[str]]:
    """The files in ``root`` that some stage writes (relative paths), by stage."""
    found: dict[str, list[str]] = {stage: [] for stage in STAGES}
    for folder in _FOLDERS:
        directory = root / folder
        if not directory.is_dir():
            continue
        for path in sorted(directory.iterdir()):
            relative = path.relative_to(root).as_posix()
            stage = stage_of(relative)
            if stage is not None and path.is_file():
                found[stage].append(relative)
    return found


class RunManifest:
    """The manifest of the run directory ``root``, read and written whole at each change."""

    def __init__(self, root: Path):
        self.root = Path(root)
        self.path = self.root / MANIFEST

    def load(self) -> Manifest | None:
        if not self.path.exists():
            return None
        doc = read_json(self.path, ManifestError)
        try:
            return Manifest.model_validate(doc)
        except ValidationError as exc:
            first = exc.errors()[0]
            where = ".".join(str(p) for p in first["loc"]) or "(document)"
            raise ManifestError(f"not a radioslam run manifest: {first['msg']}", file=self.path, field=where) from None

    def save(self, manifest: Manifest) -> None:
        atomic_write_text(self.path, manifest.model_dump_json(indent=2) + "\n")

    def _fresh(self, seed: int | None = None, scene: str | None = None) -> Manifest:
        return Manifest(run_id=uuid.uuid4().hex, created=_now(), command=invocation(), versions=versions(),
                        seed=seed, scene=scene)

    def new_run(self, seed: int, scene: str, force: bool = False, resume: bool = False) -> Manifest:
        """Start a new run here: the old run's files (those its manifest lists) are removed first; a
        directory holding anything else, and no manifest, is refused unless ``force``. With ``resume``,
        a run of the same scene and seed found here is kept, to go on from (:meth:`begin`)."""
        old = self.load()
        if resume and old is not None and old.stages:
            if (old.scene, old.seed) != (scene, seed):
                raise ManifestError(f"--resume: this directory holds a run of {old.scene!r} with seed {old.seed}, "
                                    f"not of {scene!r} with seed {seed}", file=self.path, field="scene, seed")
            return old
        if old is None and not force and self.root.is_dir() and any(self.root.iterdir()):
            raise ManifestError("holds files and no run.json: not a radioslam run; choose an empty directory or "
                                "pass --force to write into it", file=self.root, field="(directory)")
        manifest = self._fresh(seed, scene)
        if old is not None:
            manifest.removing = sorted({*old.removing, *(f for r in old.stages.values() for f in r.outputs)})
        self.root.mkdir(parents=True, exist_ok=True)
        self.save(manifest)  # the new run owns the directory before the old one's files go
        self._remove(manifest.removing)
        manifest.removing = []
        self._remove_temporary(STAGES)
        self.save(manifest)
        return manifest

    def begin(self, stage: str, settings: dict | None = None, resume: bool = False,
              external: Iterable[Path] = ()) -> set[str]:
        """Stage ``stage`` starts: the stages before it must be complete and their files on disk as
        listed; it and every stage after are invalidated (their files removed). A directory without a
        manifest is adopted first (:meth:`adopt`). The earlier files it reads (``STAGE_INPUTS``) and the
        ``external`` files it is given are recorded with their hashes as its inputs. With ``resume``,
        the files an unfinished run of this stage with the same settings recorded (:meth:`record`) and
        that still hash as recorded are kept: their relative paths are returned, for the stage to skip."""
        self._no_linked_folders(stage)
        manifest = self.load() or self.adopt(stage)
        index = STAGES.index(stage)
        verified = self._verify(manifest, STAGES[:index], stage)
        inputs = {f: h for f, h in sorted(verified.items()) if any(re.fullmatch(p, f) for p in STAGE_INPUTS[stage])}
        # a given file that is missing or not a regular one (a FIFO would block) is left to its reader to refuse
        inputs.update({str(Path(p).resolve()): file_hash(Path(p)) for p in external if Path(p).is_file()})
        settings = _as_stored(settings or {})
        kept = self._resumable(stage, manifest.stages.get(stage), settings) if resume else {}
        later = STAGES[index:]
        stale = [f for s in later if s in manifest.stages for f in manifest.stages[s].outputs if f not in kept]
        manifest.removing = sorted({*manifest.removing, *stale})  # listed until removed (a kill in between)
        for s in later:
            manifest.stages.pop(s, None)
        record = manifest.stages[stage] = StageRecord(status=StageStatus.STARTED, started=_now(),
                                                      settings=settings, inputs=inputs, outputs=kept)
        self.save(manifest)
        self._remove(manifest.removing)
        self._remove_temporary(later)
        manifest.removing = []
        record.foreign = {f: file_hash(self.root / f) for f in run_files(self.root)[stage] if f not in kept}
        self.save(manifest)
        return set(kept)

    def record(self, stage: str, paths: Iterable[Path]) -> None:
        """Files the running stage ``stage`` has finished (a pose's scan): a resumed run keeps them."""
        manifest = self._running(stage)
        run = RunDir(self.root)
        for path in paths:
            manifest.stages[stage].outputs[run.relative(path)] = file_hash(Path(path))
        self.save(manifest)

    def is_complete(self, stage: str, settings: dict | None = None) -> bool:
        """Stage ``stage`` completed here with these settings, its files as recorded (a resumed run skips it)."""
        manifest = self.load()
        record = None if manifest is None else manifest.stages.get(stage)
        return record is not None and record.status is StageStatus.COMPLETE and \
            record.settings == _as_stored(settings or {}) and \
            len(self._resumable(stage, record, record.settings)) == len(record.outputs)

    def _resumable(self, stage: str, record: StageRecord | None, settings: dict) -> dict[str, str]:
        """The outputs of ``record`` (made with ``settings``) still on disk as recorded."""
        if record is None:
            return {}
        if record.settings != settings:
            raise ManifestError("--resume: this stage ran with other settings; run without --resume",
                                file=self.path, field=f"stages.{stage}.settings")
        return {f: h for f, h in record.outputs.items() if (self.root / f).is_file() and file_hash(self.root / f) == h}

    def complete(self, stage: str) -> None:
        """Stage ``stage`` is complete: its files now in the directory are its outputs (``begin``
        removed those of the run before)."""
        manifest = self._running(stage)
        record = manifest.stages[stage]
        # a file :meth:`record` hashed (or a resumed run kept) is final: its hash is not computed again
        hashes = {f: record.outputs.get(f) or file_hash(self.root / f) for f in run_files(self.root)[stage]}
        record.outputs = {f: h for f, h in hashes.items() if record.foreign.get(f) != h}
        record.foreign = {f: h for f, h in hashes.items() if record.foreign.get(f) == h}
        record.status, record.finished = StageStatus.COMPLETE, _now()
        self.save(manifest)

    def fail(self, stage: str, error: str) -> None:
        manifest = self.load()
        if manifest is None or stage not in manifest.stages:
            return
        record = manifest.stages[stage]
        record.status, record.finished, record.error = StageStatus.FAILED, _now(), error
        self.save(manifest)

    @contextmanager
    def stage(self, stage: str, settings: dict | None = None, resume: bool = False,
              external: Iterable[Path] = ()) -> Iterator[set[str]]:
        """``begin``, the body (given the files a resumed stage kept), then ``complete``; a failure (an
        interrupt too) marks the stage failed and goes on."""
        kept = self.begin(stage, settings, resume, external)
        try:
            yield kept
        except BaseException as exc:
            self.fail(stage, f"{type(exc).__name__}: {exc}")
            raise
        self.complete(stage)

    def adopt(self, stage: str) -> Manifest:
        """A manifest for a directory without one: the files of each stage before ``stage`` found here
        become that stage's outputs (``source: found``)."""
        manifest = self._fresh()
        found = run_files(self.root)
        for earlier in STAGES[:STAGES.index(stage)]:
            if found[earlier]:
                manifest.stages[earlier] = StageRecord(
                    status=StageStatus.COMPLETE, source=Source.FOUND, started=_now(), finished=_now(),
                    outputs={f: file_hash(self.root / f) for f in found[earlier]})
        self.root.mkdir(parents=True, exist_ok=True)
        self.save(manifest)
        return manifest

    def _verify(self, manifest: Manifest, earlier: tuple[str, ...], stage: str) -> dict[str, str]:
        """Every earlier stage that ran is complete, and the files of each are on disk as listed, no more.
        Returns their hashes, as verified."""
        on_disk, verified = run_files(self.root), {}
        for name in earlier:
            record = manifest.stages.get(name)
            if record is None:
                if on_disk[name]:
                    raise ManifestError(f"not written by this run (run.json has no '{name}' stage)",
                                        file=self.root / on_disk[name][0], field="(file)")
                continue
            if record.status is not StageStatus.COMPLETE:
                why = f"failed ({record.error})" if record.status is StageStatus.FAILED else \
                    "started and never finished (killed?)"
                raise ManifestError(f"stage '{name}' {why}: the run is incomplete; run 'radioslam {name}' again "
                                    f"before '{stage}'", file=self.path, field=f"stages.{name}.status")
            for relative, digest in record.outputs.items():
                path = self.root / relative
                if not path.is_file():
                    raise ManifestError(f"missing: '{name}' wrote it and run.json lists it", file=path,
                                        field="(file)")
                if file_hash(path) != digest:
                    raise ManifestError(f"changed since '{name}' wrote it (SHA-256 differs from run.json)",
                                        file=path, field="(file)")
                verified[relative] = digest
            extra = sorted(set(on_disk[name]) - set(record.outputs))  # foreign ones included
            if extra:
                raise ManifestError(f"not part of this run (run.json lists {len(record.outputs)} files of "
                                    f"'{name}')", file=self.root / extra[0], field="(file)")
        return verified

    def _no_linked_folders(self, stage: str) -> None:
        """The folders ``stage`` writes its files into are folders of the run directory, not links (to
        elsewhere: the run's files would be written, and later replaced, outside it)."""
        for folder in sorted({p.split("/")[0] for p in STAGE_FILES[stage] if "/" in p}):
            path = self.root / folder
            if path.is_symlink():
                raise ManifestError(f"a symbolic link (to {os.readlink(path)}): a run's files are written only inside "
                                    "the run directory, never through a link; remove the link, or give --out a "
                                    "directory where the files should go", file=path, field="(directory)")

    def _running(self, stage: str) -> Manifest:
        manifest = self.load()
        if manifest is None or stage not in manifest.stages:
            raise ManifestError(f"stage '{stage}' was not started here (another process replaced the run?)",
                                file=self.path, field=f"stages.{stage}")
        return manifest

    def _inside(self, relative: str) -> Path | None:
        """The file at ``relative`` if it lies in the run directory itself, reached through no link."""
        path = self.root / relative
        if path.parent.is_symlink() or path.parent.resolve() != (self.root.resolve() / relative).parent:
            return None
        return path

    def _remove(self, relatives: Iterable[str]) -> None:
        for relative in relatives:
            path = self._inside(relative)
            if path is not None and (path.is_file() or path.is_symlink()):
                path.unlink()

    def _remove_temporary(self, stages: Iterable[str]) -> None:
        """What killed writers of these stages' files left: ``.NAME.XXXXXXXX.tmp`` (:mod:`atomic`)."""
        names = tuple(stages)
        for folder in _FOLDERS:
            directory = self.root / folder
            if not directory.is_dir() or directory.is_symlink():
                continue
            for path in directory.glob(".*.tmp"):
                match = re.fullmatch(r"\.(.+)\.[^.]+\.tmp", path.name)
                target = (Path(folder) / match.group(1)).as_posix() if match else None
                if target is not None and stage_of(target) in names:
                    path.unlink(missing_ok=True)
