"""The ``radioslam`` command (DESIGN.md §6 ★): the typer app and its top-level options."""

from __future__ import annotations

import typer

from radioslam.cli.options import CONTEXT, quiet_option, verbose_option
from radioslam.cli.output import set_verbosity

app = typer.Typer(add_completion=False, invoke_without_command=True, pretty_exceptions_enable=False,
                  rich_markup_mode=None, context_settings=CONTEXT)  # its help: _root's docstring


def _version(value: bool) -> None:
    if value:
        from radioslam import __version__

        typer.echo(f"radioslam {__version__}")
        raise typer.Exit()


@app.callback()
def _root(ctx: typer.Context,
          version: bool = typer.Option(False, "--version", callback=_version, is_eager=True,
                                       help="print the version and exit"),
          quiet: bool = quiet_option(),
          verbose: int = verbose_option()) -> None:
    """Active mmWave sensing SLAM in 5G NR (arXiv 2507.04662): simulate a terminal's beam sweeps as waveform IQ,
    sense them into radio point clouds, map and localize."""
    set_verbosity(quiet, verbose)
    if ctx.invoked_subcommand is None:
        typer.echo(ctx.get_help())
        raise typer.Exit()
