"""Command line (DESIGN.md §6 ★): ``radioslam``. The application's top layer: it imports the pipeline, the
core and the figures, lazily inside each command so that ``--help`` stays quick; nothing imports it.

Modules: ``app`` (the typer app and its top-level options), ``options`` (what the commands share),
``output`` (how it speaks and ends), ``stages`` (one command per stage), ``runs`` (whole runs, the
paper's experiments, sweeps)."""

from __future__ import annotations

import signal
import sys
import warnings

import typer

from radioslam.cli import runs, stages  # noqa: F401 - the commands register themselves on the app
from radioslam.cli.app import app
from radioslam.cli.output import TERMINATED, Interrupted, Terminated, err, report_warnings, reset_verbosity, terminate

__all__ = ["app", "main"]


def main() -> None:
    """Entry point: usage errors and interrupts end in one line too.

    typer ≤ 0.2x raises click's exceptions, newer typer its vendored copy of them;
    both carry ``format_message()`` and ``exit_code``, which is all this needs. Warnings of the
    numerical libraries (a log of zero, an empty mean) are counted, not printed line by line.
    """
    reset_verbosity()
    command = typer.main.get_command(app)
    signal.signal(signal.SIGTERM, terminate)
    try:
        with warnings.catch_warnings(record=True) as caught:  # the filters as they are: libraries' deprecations
            code = command.main(prog_name="radioslam", standalone_mode=False)
        if not code:
            report_warnings(caught)
    except Terminated:
        err.print("radioslam: terminated (SIGTERM); unfinished stages are marked failed in run.json")
        sys.exit(TERMINATED)
    except (Interrupted, KeyboardInterrupt):
        err.print("radioslam: interrupted (Ctrl-C); unfinished stages are marked failed in run.json")
        sys.exit(130)
    except Exception as exc:  # noqa: BLE001 - only click-style exceptions are handled here
        if type(exc).__name__ == "Abort":
            err.print("radioslam: interrupted (Ctrl-C)")
            sys.exit(130)
        if not (hasattr(exc, "format_message") and hasattr(exc, "exit_code")):
            raise
        ctx = getattr(exc, "ctx", None)
        where = f"{ctx.command_path}: " if ctx is not None else ""
        err.print(f"radioslam: error: {where}{exc.format_message()}", markup=False, soft_wrap=True)
        sys.exit(exc.exit_code)
    sys.exit(code if isinstance(code, int) else 0)
