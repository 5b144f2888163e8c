"""The whole-run commands (DESIGN.md §6 ★): ``run`` and ``demo`` (every stage, every stage's options),
``reproduce`` (the paper's experiments), ``sweep`` (Monte Carlo on Dask) and ``scenes``."""

from __future__ import annotations

import inspect
from pathlib import Path
from typing import Optional

import typer

from radioslam.choices import ChannelKind, Detector, Experiment, ImpairmentProfile, PointFilter, Refinement
from radioslam.cli import options as opt
from radioslam.cli.app import app
from radioslam.cli.options import register
from radioslam.cli.output import detail, gib, info, progress
from radioslam.cli.stages import print_metrics, report_slam

DEMO_SCENE = "paper-cnv"


@register(app)
def scenes() -> None:
    """List the built-in scenes."""
    from radioslam.scene import BUILTIN_SCENES

    for name, (_, summary) in BUILTIN_SCENES.items():
        typer.echo(f"{name:14s} {summary}")


def _run_all(scene: str, out: Path, json_out: bool, strict: bool, config: Optional[Path], sensing: dict,
             **settings) -> None:
    """Every stage of one run, then report.html; the metrics on stdout."""
    from radioslam.pipeline import RunOptions, report_stage, run_scene

    cfg = opt.run_config(config, sensing)
    settings["max_memory"] = gib(settings["max_memory"])
    options = RunOptions(radio=cfg.radio, sensing=cfg.sensing, slam=cfg.slam, **settings)
    detail(f"run: {scene} into {out}, seed {options.seed}, channel {ChannelKind(options.channel).value}, "
           f"{'IQ written to captures/' if options.save_iq else 'IQ sensed in memory'}")
    with progress() as shown:
        result, metrics = run_scene(scene, out, options, shown)
    report_stage(out)
    detail("seconds per stage: " + ", ".join(f"{k} {v:.1f}" for k, v in metrics.get("timings_s", {}).items()))
    print_metrics(metrics, json_out)
    info(f"wrote {out} (report.html)")
    report_slam(result, strict)


@register(app)
def run(
    scene: str = opt.scene_argument(),
    out: Path = opt.out_option(),
    seed: int = opt.seed_option(),
    snr_db: Optional[float] = opt.snr_option(),
    json_out: bool = opt.json_option(),
    config: Optional[Path] = opt.config_option(),
    save_iq: bool = opt.save_iq_option(),
    channel: ChannelKind = opt.channel_option(),
    detector: Optional[Detector] = opt.detector_option(),
    threshold_db: Optional[float] = opt.threshold_option(),
    point_filter: Optional[PointFilter] = opt.point_filter_option(),
    refine: Optional[Refinement] = opt.refine_option(),
    plot_pose: int = opt.plot_pose_option(),
    odometry: Optional[Path] = typer.Option(None, "--odometry", help=opt.ODOMETRY_HELP + "; 'simulated': the "
                                            "scene's own (odometry.tum), at the scene's stated noise"),
    strict: bool = opt.strict_option(),
    scene_frame: bool = opt.scene_frame_option(),
    force: bool = opt.force_option(),
    max_memory: Optional[float] = opt.max_memory_option(),
    resume: bool = opt.resume_option(),
) -> None:
    """Run simulate → sense → slam → evaluate on any scene, and write report.html.

    A new run: whatever run the directory held is replaced. Every stage's options are here; a config file's
    radio:, sensing: and slam: sections set the rest.
    """
    _run_all(scene, out, json_out, strict, config, opt.sensing_overrides(detector, threshold_db, point_filter, refine),
             seed=seed, snr_db=snr_db, save_iq=save_iq, channel=channel, plot_pose=plot_pose, odometry=odometry,
             scene_frame=scene_frame, force=force, max_memory=max_memory, resume=resume)


def demo(**options) -> None:
    """Run the paper's Fig. 6 simulation end to end: paper-cnv, 60 poses on a 5 m circle, SNR 10 dB, waveform IQ.

    The same as 'radioslam run paper-cnv --out runs/demo', with every option of run but --odometry.
    """
    run.__wrapped__(DEMO_SCENE, odometry=None, **options)


# demo's options are run's: its signature, without the scene and --odometry, --out defaulting to runs/demo
_run_signature = inspect.signature(run.__wrapped__)
demo.__signature__ = _run_signature.replace(parameters=[
    p.replace(default=opt.out_option(default=Path("runs/demo"))) if p.name == "out" else p
    for p in _run_signature.parameters.values() if p.name not in ("scene", "odometry")])
demo.__annotations__ = {k: v for k, v in run.__wrapped__.__annotations__.items() if k not in ("scene", "odometry")}
register(app)(demo)


@register(app)
def reproduce(
    experiment: Experiment = typer.Argument(..., help="which: the paper's Table I, Fig. 5, Fig. 8, Fig. 6, Table I "
                                            "under each hardware impairment, or all"),
    out: Path = opt.out_option("directory for the figures (PNG) and tables (CSV, Markdown)"),
    json_out: bool = typer.Option(False, "--json", help="print one JSON object of the results on stdout"),
    seed: int = opt.seed_option(),
    trials: Optional[int] = typer.Option(None, "--trials", min=1, help="Monte Carlo trials (default per experiment)"),
    impairments: ImpairmentProfile = typer.Option(ImpairmentProfile.IDEAL, "--impairments",
                                                  help="table1: the radio's hardware profile "
                                                       "(docs/architecture.md, Hardware impairments)"),
) -> None:
    """Reproduce the paper's experiments (Table I, Fig. 5, Fig. 8, Fig. 6) and Table I under hardware impairments."""
    from radioslam.eval.experiments.reproduce import run_experiment
    from radioslam.io.json_io import dumps

    names = [e.value for e in Experiment if e is not Experiment.ALL] if experiment is Experiment.ALL \
        else [Experiment(experiment).value]
    out.mkdir(parents=True, exist_ok=True)
    results = {}
    with progress() as shown:
        for k, name in enumerate(names):
            detail(f"reproduce {name} ({k + 1}/{len(names)})")
            results[name] = run_experiment(name, out, seed, trials, ImpairmentProfile(impairments).value, shown)
    if json_out:
        typer.echo(dumps(results[names[0]] if len(names) == 1 else results))
    info(f"wrote {', '.join(names)} to {out}")


@register(app)
def sweep(
    sweep_file: Path = typer.Argument(..., help="sweep YAML: scenes, seeds, snr_db, overrides, variants, robustness"),
    out: Path = opt.out_option("sweep directory: runs/, rows/, results.parquet, results.csv, plots"),
    scheduler: Optional[str] = typer.Option(None, "--scheduler", help="a running Dask scheduler (tcp://HOST:8786; "
                                            "its workers must see --out), or 'synchronous' (one by one, in this "
                                            "process); default: a LocalCluster"),
    workers: Optional[int] = typer.Option(None, "--workers", min=1, help="LocalCluster worker processes (default: "
                                          "one per core)"),
    retry_failed: bool = typer.Option(False, "--retry-failed", help="run again the runs that failed before"),
) -> None:
    """Run a Monte Carlo sweep on Dask: every scene × seed × SNR × variant as a whole run; a tidy table and plots."""
    from radioslam.sweep import load_sweep, run_sweep

    spec = load_sweep(sweep_file)

    def report(row: dict, done: int, total: int) -> None:
        what = f"ATE {row['ate_rmse_m']:.3f} m" if row["status"] == "ok" else row["error"]
        info(f"[{done}/{total}] {row['scene']} seed {row['seed']} snr {row['snr_db']}: {row['status']}, {what} "
             f"({row['run_seconds']:.0f} s)")

    result = run_sweep(spec, out, scheduler, workers, retry_failed, report)
    info(f"wrote {out}/results.parquet and results.csv: {len(result.table)} runs ({result.ran} run now, "
         f"{result.skipped} finished before, {result.failed} failed) in {result.seconds:.0f} s")
