"""Command line (DESIGN.md §6 ★). Bad input exits with status 2 and one line."""

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

app = typer.Typer(add_completion=False, invoke_without_command=True, pretty_exceptions_enable=False,
                  rich_markup_mode=None, help="Active mmWave sensing SLAM in 5G NR (arXiv 2507.04662).")
err = Console(stderr=True, highlight=False)


def _version(value: bool) -> None:
    if value:
        from radioslam import __version__

        typer.echo(f"radioslam {__version__}")
        raise typer.Exit()


@app.callback()
def _root(ctx: typer.Context,
          version: bool = typer.Option(False, "--version", callback=_version, is_eager=True,
                                       help="print the version and exit")) -> None:
    """Active mmWave sensing SLAM in 5G NR (arXiv 2507.04662)."""
    if ctx.invoked_subcommand is None:
        typer.echo(ctx.get_help())
        raise typer.Exit()


def _fail(message: str) -> None:
    err.print(f"radioslam: error: {message}", markup=False, soft_wrap=True)
    raise typer.Exit(2)


def one_line_errors(command: Callable) -> Callable:
    """Turn bad input into exit status 2 and one line on stderr: no traceback."""

    @wraps(command)
    def wrapper(*args, **kwargs):
        try:
            return command(*args, **kwargs)
        except RadioslamError as exc:
            _fail(exc.one_line())
        except OSError as exc:
            _fail(f"{exc.filename or '(file)'}: (file): {exc.strerror or exc}")

    return wrapper


def progress() -> Progress:
    """A progress bar on stderr, shown only on a terminal."""
    return Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeRemainingColumn(),
                    console=err, disable=not sys.stderr.isatty(), transient=True)


@app.command()
@one_line_errors
def scenes() -> None:
    """List the built-in scenes."""
    from radioslam.scene import BUILTIN_SCENES

    for name, (_, summary) in BUILTIN_SCENES.items():
        typer.echo(f"{name:14s} {summary}")


@app.command()
@one_line_errors
def simulate(
    scene: str = typer.Argument(..., help="scene YAML file or built-in name (see 'radioslam scenes')"),
    out: Path = typer.Option(..., "--out", help="run directory to write"),
    seed: int = typer.Option(0, "--seed", min=0, help="seed of every random draw (≥ 0)"),
    snr_db: Optional[float] = typer.Option(None, "--snr-db", help="per-RE SNR of the reference echo, dB"),
    save_iq: bool = typer.Option(False, "--save-iq", help="write SigMF captures/NNNN.sigmf-{meta,data}"),
) -> None:
    """Simulate a scene: scene.yaml, ground_truth.tum and, with --save-iq, SigMF captures."""
    from radioslam.io import write_capture, write_tum
    from radioslam.io.atomic import atomic_write_text
    from radioslam.io.rundir import RunDir
    from radioslam.scene import load_scene, scene_to_yaml
    from radioslam.sim import Simulator

    loaded = load_scene(scene).with_radio(snr_db=snr_db)
    run = RunDir(out)
    run.root.mkdir(parents=True, exist_ok=True)
    run.clear_captures()  # a run directory never mixes recordings of two runs
    atomic_write_text(run.scene, scene_to_yaml(loaded))
    write_tum(run.ground_truth, run.pose_timestamps(len(loaded.poses)), loaded.poses)
    if save_iq:
        sim = Simulator.from_scene(loaded)
        with progress() as bar:
            task = bar.add_task("simulating", total=len(loaded.poses))
            for capture in sim.simulate(seed):
                write_capture(capture, run.capture_base(capture.pose_index))
                bar.advance(task)
    err.print(f"wrote {run.root} ({len(loaded.poses)} poses{', IQ captures' if save_iq else ''})",
              markup=False)


def main() -> None:
    """Entry point: usage errors and interrupts end in one line too.

    typer ≤ 0.2x raises click's exceptions, newer typer its vendored copy of them;
    both carry ``format_message()`` and ``exit_code``, which is all this needs.
    """
    command = typer.main.get_command(app)
    try:
        code = command.main(prog_name="radioslam", standalone_mode=False)
    except KeyboardInterrupt:
        err.print("radioslam: interrupted", markup=False)
        sys.exit(130)
    except Exception as exc:  # noqa: BLE001 - only click-style exceptions are handled here
        if type(exc).__name__ == "Abort":
            err.print("radioslam: interrupted", markup=False)
            sys.exit(130)
        if not (hasattr(exc, "format_message") and hasattr(exc, "exit_code")):
            raise
        ctx = getattr(exc, "ctx", None)
        where = f"{ctx.command_path}: " if ctx is not None else ""
        err.print(f"radioslam: error: {where}{exc.format_message()}", markup=False, soft_wrap=True)
        sys.exit(exc.exit_code)
    sys.exit(code if isinstance(code, int) else 0)


if __name__ == "__main__":
    main()
