"""How the command line speaks and ends (DESIGN.md §6 ★; issue #15): one line on stderr and exit
status 2 for bad input, 130 for Ctrl-C and 143 for SIGTERM; user strings printed as they are (no
markup, no emoji codes, no wrapping); a progress bar only on a terminal; the shared option helps."""

from __future__ import annotations

import sys
from collections.abc import Callable
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


class _NoProgress:
    """What a progress bar does off a terminal: nothing (rich < 13.4 writes a newline even when disabled)."""

    def __enter__(self) -> "_NoProgress":
        return self

    def __exit__(self, *exc) -> None:
        return None

    def add_task(self, *args, **kwargs) -> int:
        return 0

    def advance(self, *args, **kwargs) -> None:
        return None


def progress() -> Progress | _NoProgress:
    """A progress bar on stderr, shown only on a terminal."""
    if not sys.stderr.isatty():
        return _NoProgress()
    return Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeRemainingColumn(),
                    console=err, transient=True)


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
