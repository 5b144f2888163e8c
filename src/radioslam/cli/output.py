"""How the command line speaks and ends (DESIGN.md §6 ★; issues #15, #17): one line on stderr and exit
status 2 for bad input, 130 for Ctrl-C and 143 for SIGTERM; user strings printed as they are (no markup,
no emoji codes, no wrapping); how much it says (``-q`` errors and warnings only, ``-v`` each stage's
details too); progress as a bar on a terminal and as a line every ``PROGRESS_INTERVAL_S`` elsewhere."""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable
from enum import IntEnum
from functools import wraps
from pathlib import Path
from typing import Optional

import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

from radioslam.errors import RadioslamError

# user strings (file names, reasons) are never markup or emoji codes (':radio:'), and a line never wraps
err = Console(stderr=True, highlight=False, emoji=False, markup=False, soft_wrap=True)
TERMINATED = 143  # 128 + SIGTERM, as a shell reports it
# seconds between two progress lines off a terminal (RADIOSLAM_PROGRESS_INTERVAL overrides it, for tests)
PROGRESS_INTERVAL_S = 10.0


class Verbosity(IntEnum):
    QUIET = 0  # errors and warnings
    NORMAL = 1  # and what was written, and progress
    VERBOSE = 2  # and each stage's settings and seconds


_verbosity = Verbosity.NORMAL


def set_verbosity(quiet: bool, verbose: int) -> None:
    """-q wins over -v; -v given at the top (``radioslam -v run``) or after the command counts alike."""
    global _verbosity
    if quiet:
        _verbosity = Verbosity.QUIET
    elif verbose:
        _verbosity = Verbosity.VERBOSE


def reset_verbosity() -> None:
    global _verbosity
    _verbosity = Verbosity.NORMAL


def info(message: str) -> None:
    """What a command did (``wrote DIR``): not with -q."""
    if _verbosity >= Verbosity.NORMAL:
        err.print(message, markup=False)


def detail(message: str) -> None:
    """A stage's settings and timings: with -v only."""
    if _verbosity >= Verbosity.VERBOSE:
        err.print(f"radioslam: {message}", markup=False)


def warn(message: str) -> None:
    err.print(f"radioslam: warning: {message}", markup=False)


class Interrupted(BaseException):
    """Ctrl-C during a command (its temporary files are gone and its stage marked failed on the way out)."""


class Terminated(BaseException):
    """SIGTERM, raised where the process is, so that the way out is the same as after Ctrl-C."""


def fail(message: str) -> None:
    err.print(f"radioslam: error: {message}", markup=False, soft_wrap=True)
    raise typer.Exit(2)


def one_line_errors(command: Callable) -> Callable:
    """Turn bad input into exit status 2 and one line on stderr: no traceback."""

    @wraps(command)
    def wrapper(*args, **kwargs):
        try:
            return command(*args, **kwargs)
        except RadioslamError as exc:
            fail(exc.one_line())
        except OSError as exc:  # every writer and reader names its file (io.atomic); else the reason alone
            named = exc.filename is not None
            fail(RadioslamError(exc.strerror or str(exc), file=exc.filename, field="(file)" if named else None)
                 .one_line())
        except KeyboardInterrupt:  # not click's: it would print a blank line first
            raise Interrupted() from None

    return wrapper


def out_path(value: str) -> Path:
    """An --out path: an empty one would be the working directory, so it is refused."""
    if not str(value).strip():
        raise typer.BadParameter("an empty path: name the directory or file to write")
    return Path(value)


class _Silent:
    """No progress (-q)."""

    def start(self, description: str, total: int, completed: int = 0) -> None:
        return None

    def advance(self, steps: int = 1) -> None:
        return None


class _Bar:
    """A rich progress bar on stderr, one task per stage (:class:`radioslam.progress.Progress`)."""

    def __init__(self) -> None:
        self.bar = Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                            TimeRemainingColumn(), console=err, transient=True)
        self.task = None

    def start(self, description: str, total: int, completed: int = 0) -> None:
        if self.task is not None:
            self.bar.remove_task(self.task)
        self.task = self.bar.add_task(description, total=total, completed=completed)

    def advance(self, steps: int = 1) -> None:
        if self.task is not None:
            self.bar.advance(self.task, steps)


class _Lines:
    """Off a terminal (a pipe, a log file, CI): a line per stage every ``interval`` seconds, with what is
    done, the rate and the time left, and one when a stage that took longer ends."""

    def __init__(self, interval: float) -> None:
        self.interval, self.stage = interval, None

    def start(self, description: str, total: int, completed: int = 0) -> None:
        self._finish()
        now = time.monotonic()
        self.stage = {"description": description, "total": total, "done": completed, "first": completed,
                      "start": now, "said": now, "lines": 0}

    def advance(self, steps: int = 1) -> None:
        if self.stage is None:
            return
        self.stage["done"] += steps
        now = time.monotonic()
        if now - self.stage["said"] >= self.interval and self.stage["done"] < self.stage["total"]:
            self._say(now)

    def _say(self, now: float) -> None:
        s = self.stage
        rate = (s["done"] - s["first"]) / max(now - s["start"], 1e-9)
        left = (s["total"] - s["done"]) / rate if rate > 0 else float("inf")
        eta = f"ETA {left:.0f} s" if left != float("inf") else "ETA unknown"
        err.print(f"radioslam: {s['description']}: {s['done']}/{s['total']} ({rate:.2g}/s, {eta})", markup=False)
        s["said"], s["lines"] = now, s["lines"] + 1

    def _finish(self) -> None:
        s, self.stage = self.stage, None
        if s is not None and s["lines"]:  # a stage long enough to have spoken says when it ends
            err.print(f"radioslam: {s['description']}: {s['done']}/{s['total']} in "
                      f"{time.monotonic() - s['start']:.0f} s", markup=False)

    def close(self) -> None:
        self._finish()


class progress:  # noqa: N801 - used as a context manager, like rich's
    """The progress a command shows (:class:`radioslam.progress.Progress`): none with -q, a bar on a terminal,
    lines elsewhere."""

    def __enter__(self):
        if _verbosity <= Verbosity.QUIET:
            self.shown = _Silent()
        elif sys.stderr.isatty():
            self.shown = _Bar()
            self.shown.bar.__enter__()
        else:
            self.shown = _Lines(float(os.environ.get("RADIOSLAM_PROGRESS_INTERVAL", PROGRESS_INTERVAL_S)))
        return self.shown

    def __exit__(self, *exc) -> None:
        if isinstance(self.shown, _Bar):
            self.shown.bar.__exit__(*exc)
        elif isinstance(self.shown, _Lines) and exc[0] is None:
            self.shown.close()


RESUME_HELP = ("go on with an unfinished run of the same scene, seed and settings in --out (killed, or failed): "
               "the poses it finished, verified by their hashes in run.json, are not done again")
MAX_MEMORY_HELP = ("GiB one pose may need (estimated before anything is allocated; default: half the machine's "
                   "memory); beyond it, exit 2 naming the field")
FORCE_HELP = ("write into a directory that holds other files and no run.json (none of them is removed; "
              "same-named ones are overwritten)")


def gib(value: Optional[float]) -> Optional[int]:
    return None if value is None else int(value * 2**30)


def terminate(signum, frame) -> None:
    raise Terminated()


def report_warnings(caught: list) -> None:
    """One line for the warnings a successful command met (none for an error: that is its one line)."""
    if caught:
        first = caught[0]
        err.print(f"radioslam: note: {len(caught)} warning(s) from the numerical libraries, the first: "
                  f"{first.category.__name__}: {' '.join(str(first.message).split())}")
