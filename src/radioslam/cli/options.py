"""What the commands share (issue #17): the registration that gives every command ``-h``, ``-q`` and ``-v``
and one-line errors; the options several commands take, each defined once with its help."""

from __future__ import annotations

import inspect
from collections.abc import Callable
from functools import wraps
from pathlib import Path
from typing import Optional

import typer

from radioslam.choices import ChannelKind, Detector, PointFilter, Refinement
from radioslam.cli.output import FORCE_HELP, MAX_MEMORY_HELP, RESUME_HELP, one_line_errors, out_path, set_verbosity

CONTEXT = {"help_option_names": ["-h", "--help"]}
DEFAULT_SEED = 0  # one default for every command that draws


def register(app: typer.Typer, name: Optional[str] = None) -> Callable[[Callable], Callable]:
    """``@register(app)``: the function as a command of ``app``, with ``-h``, ``-q/--quiet`` and
    ``-v/--verbose`` added to its options, bad input turned into one line
    (:func:`~radioslam.cli.output.one_line_errors`), and its docstring's first paragraph, whole, as its
    summary in ``radioslam --help``."""

    def decorate(function: Callable) -> Callable:
        guarded = one_line_errors(function)

        @wraps(function)
        def command(*args, quiet: bool = False, verbose: int = 0, **kwargs):
            set_verbosity(quiet, verbose)
            return guarded(*args, **kwargs)

        signature = inspect.signature(function)
        extra = [inspect.Parameter("quiet", inspect.Parameter.KEYWORD_ONLY, annotation="bool",
                                   default=quiet_option()),
                 inspect.Parameter("verbose", inspect.Parameter.KEYWORD_ONLY, annotation="int",
                                   default=verbose_option())]
        command.__signature__ = signature.replace(parameters=[*signature.parameters.values(), *extra])
        command.__annotations__ = {**function.__annotations__, "quiet": "bool", "verbose": "int"}
        summary = " ".join(inspect.getdoc(function).split("\n\n")[0].split())  # whole, not cut at a period
        return app.command(name, context_settings=CONTEXT, short_help=summary)(command)

    return decorate


QUIET_HELP = "say nothing but errors and warnings (no progress, no 'wrote ...')"
VERBOSE_HELP = "say more: each stage's settings and seconds"
SEED_HELP = "seed of every random draw: noise, payloads, calibration (the same seed, the same run)"
SNR_HELP = "per-RE SNR of the reference echo, dB (default: the scene's radio, 10 dB)"
CONFIG_HELP = ("YAML config file with radio:, sensing: and slam: sections (docs/architecture.md, Config file); "
               "options given here override it")
CHANNEL_HELP = ("where the echo paths come from: the built-in 2D caster, or Sionna RT on the scene extruded to 3D "
                "(extrude: in the scene; pip install 'radioslam[sionna]')")
ODOMETRY_HELP = ("relative motion from wheels or an IMU, one TUM pose per scan (its noise per step: "
                 "slam.motion.odometry_sigma_m and odometry_sigma_deg in --config; default a loose 5 cm and 2°)")
STRICT_HELP = ("exit with status 3 when tracking was lost (a stretch of scans matched nothing, or a long "
               "one in which none fixed one pose: a direction nothing fixes, rival poses alike), or when another "
               "trajectory is within odds of 1 : 20 of the answer (ambiguous_trajectory)")
JSON_HELP = "print one JSON object of the metrics on stdout"
SAVE_IQ_HELP = "write SigMF captures/NNNN.sigmf-{meta,data} (28 MB a pose) and sense them from the files"
SCENE_FRAME_HELP = ("also write trajectory_scene.tum: the trajectory in the scene's frame (trajectory.tum is in "
                    "the map frame, the terminal's at the first pose), for 'evo_ape tum ground_truth.tum "
                    "trajectory_scene.tum' without -a; needs ground_truth.tum (a simulated run)")
PLOT_POSE_HELP = "pose whose radar heatmap and cloud scans/NNNN.png shows (paper Fig. 4(b)); −1: none"


def quiet_option():
    return typer.Option(False, "-q", "--quiet", help=QUIET_HELP)


def verbose_option():
    return typer.Option(0, "-v", "--verbose", count=True, show_default=False, help=VERBOSE_HELP)


def scene_argument():
    return typer.Argument(..., help="scene YAML file or built-in name (see 'radioslam scenes')")


def seed_option():
    return typer.Option(DEFAULT_SEED, "--seed", min=0, help=SEED_HELP)


def out_option(help_text: str = "run directory to write", default=...):
    return typer.Option(default, "--out", parser=out_path, help=help_text)


def snr_option():
    return typer.Option(None, "--snr-db", help=SNR_HELP)


def config_option():
    return typer.Option(None, "--config", help=CONFIG_HELP)


def channel_option():
    return typer.Option(ChannelKind.BUILTIN, "--channel", help=CHANNEL_HELP)


def force_option():
    return typer.Option(False, "--force", help=FORCE_HELP)


def max_memory_option():
    return typer.Option(None, "--max-memory", min=0.01, help=MAX_MEMORY_HELP)


def resume_option():
    return typer.Option(False, "--resume", help=RESUME_HELP)


def json_option():
    return typer.Option(False, "--json", help=JSON_HELP)


def strict_option():
    return typer.Option(False, "--strict", help=STRICT_HELP)


def save_iq_option():
    return typer.Option(False, "--save-iq", help=SAVE_IQ_HELP)


def scene_frame_option():
    return typer.Option(False, "--scene-frame", help=SCENE_FRAME_HELP)


def plot_pose_option():
    return typer.Option(0, "--plot-pose", help=PLOT_POSE_HELP)


def detector_option():
    return typer.Option(None, "--detector", help="targets per beam: single (the paper's strongest peak; "
                        "default) or multi (CFAR + successive cancellation)")


def threshold_option():
    return typer.Option(None, "--threshold-db", max=0.0, help="point threshold, dB (default −13 single, −25 multi)")


def point_filter_option():
    return typer.Option(None, "--point-filter", help="single detector: same-range (default: threshold re. the "
                        "strongest detection at each range, floor −25 dB) or scan-peak (the paper's: re. the "
                        "scan's peak)")


def refine_option():
    return typer.Option(None, "--refine", help="peak refinement: bracketed (default: both sides of each peak "
                        "bracketed) or paper-bisection (the paper's, to reproduce it)")


def sensing_overrides(detector: Optional[Detector], threshold_db: Optional[float],
                      point_filter: Optional[PointFilter], refine: Optional[Refinement]) -> dict:
    """The receiver fields the sensing options set (those given)."""
    given = {"detector": detector, "point_threshold_db": threshold_db, "point_filter": point_filter,
             "refine": refine}
    return {key: value for key, value in given.items() if value is not None}


def run_config(config: Optional[Path], sensing: dict | None = None):
    """The config file's sections (:mod:`radioslam.run_config`), the sensing options given on the command
    line over its ``sensing:``."""
    from radioslam.run_config import load_run_config

    loaded = load_run_config(config)
    if sensing:
        loaded = type(loaded)(loaded.radio, loaded.sensing.model_copy(update=sensing), loaded.slam)
    return loaded
