"""Runs an experiment and writes its figure and table (the I/O side of ``radioslam reproduce``)."""

from __future__ import annotations

from pathlib import Path

from radioslam.eval.experiments.fig5 import MODES, run_fig5
from radioslam.eval.experiments.fig8 import RANGES_M, run_fig8
from radioslam.eval.experiments.impairments import PROFILES, run_impairment_table, table1_under
from radioslam.io.tables import write_table
from radioslam.progress import SILENT, Progress


def _table1(out: Path, seed: int, trials: int | None, progress: Progress, impairments: str = "ideal") -> dict:
    """Table I; under ``impairments`` (a name of :data:`PROFILES`) the radio has that hardware."""
    from radioslam.viz.figures import table1_figure

    r = table1_under(impairments, trials=trials or 50, seed=seed, progress=progress)
    write_table(out / "table1", ["range_m", "err_ifft_m", "err_bisection_m", "err_paper_bisection_m"],
                [[float(a), float(b), float(c), float(d)]
                 for a, b, c, d in zip(r.ranges_m, r.err_ifft_m, r.err_bisection_m, r.err_paper_bisection_m)])
    write_table(out / "table1_crb", ["snr_db", "rmse_bisection_m", "crb_m", "ratio"],
                [[float(s), float(e), float(c), float(e / c)] for s, e, c in zip(r.crb_snr_db, r.crb_rmse_m, r.crb_m)])
    table1_figure(out / "table1.png", r)
    return {**r.to_json(), "impairments": impairments}


def _fig5(out: Path, seed: int, trials: int | None, progress: Progress) -> dict:
    from radioslam.viz.figures import fig5_figure

    r = run_fig5(trials=trials or 30, seed=seed, progress=progress)
    rows = [[float(s)] + [float(r.peak_sidelobe_db[m][i]) for m in MODES] + [float(r.mean_sidelobe_db[m][i])
                                                                             for m in MODES]
            for i, s in enumerate(r.snr_db)]
    write_table(out / "fig5", ["snr_db"] + [f"peak_{m}_db" for m in MODES] + [f"mean_{m}_db" for m in MODES], rows)
    fig5_figure(out / "fig5.png", r)
    return r.to_json()


def _fig8(out: Path, seed: int, trials: int | None, progress: Progress) -> dict:
    from radioslam.viz.figures import fig8_figure

    r = run_fig8(trials=trials or 100, seed=seed, progress=progress)
    write_table(out / "fig8", ["method", "detect_rate_9m"],
                [["PDP peaks", r.detect_rate_pdp], ["MF + successive cancellation", r.detect_rate_mf]])
    fig8_figure(out / "fig8.png", r, RANGES_M)
    return r.to_json()


def _fig6(out: Path, seed: int, trials: int | None, progress: Progress) -> dict:
    """Fig. 6: the whole pipeline on paper-cnv (one run; ``trials`` does not apply), its run
    directory kept under fig6-run/ with report.html."""
    import shutil

    from radioslam.pipeline import RunOptions, report_stage, run_scene

    run = out / "fig6-run"
    _, metrics = run_scene("paper-cnv", run, RunOptions(seed=seed), progress)
    report_stage(run)
    shutil.copyfile(run / "fig6.png", out / "fig6.png")
    write_table(out / "fig6", ["metric", "value"],
                [[k, v] for k, v in metrics.items() if isinstance(v, (int, float))])
    return metrics


def _impairments(out: Path, seed: int, trials: int | None, progress: Progress) -> dict:
    """Table I's ranging RMSE under each hardware impairment alone and under the prototype's profile."""
    rows = run_impairment_table(trials=trials or 20, seed=seed, progress=progress)
    write_table(out / "impairments", ["profile", "rmse_ifft_m", "rmse_refined_m", "rmse_paper_bisection_m",
                                      "hardware_delay_error_s"],
                [[r.profile, r.rmse_ifft_m, r.rmse_refined_m, r.rmse_paper_bisection_m, r.hardware_delay_error_s]
                 for r in rows])
    return {"rows": [r.to_json() for r in rows]}


EXPERIMENTS = {"table1": _table1, "fig5": _fig5, "fig8": _fig8, "fig6": _fig6, "impairments": _impairments}
IMPAIRMENT_PROFILES = tuple(PROFILES)


def run_experiment(name: str, out: Path, seed: int, trials: int | None, impairments: str = "ideal",
                   progress: Progress = SILENT) -> dict:
    """One experiment; ``impairments`` applies to Table I only (the others run on the ideal radio)."""
    if name == "table1":
        return _table1(out, seed, trials, progress, impairments)
    return EXPERIMENTS[name](out, seed, trials, progress)
