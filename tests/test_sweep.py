"""Monte Carlo sweeps on Dask (issue #14): the sweep file, the tidy table, a failing run as a row,
resuming, and the same rows from a 2-worker LocalCluster and from Dask's synchronous scheduler."""

import json
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

from radioslam.sweep import SweepError, load_sweep, run_sweep

SWEEP = """
scenes: [single-plate:3, no-such-scene]
seeds: [1, 2]
snr_db: [10, 20]
"""
STAR_COLUMNS = ["scene", "seed", "snr_db", "status", "error"]  # ★, in this order, then every metrics.json key


def _sweep_file(tmp_path, text=SWEEP):
    path = tmp_path / "sweep.yaml"
    path.write_text(text)
    return path


def _deterministic(table: pd.DataFrame) -> pd.DataFrame:
    """The table without what depends on the machine (timings) or the order runs finished in."""
    kept = [c for c in table.columns if not c.startswith("timings_s.") and c not in ("run_seconds", "slam_ms_per_scan")]
    return table[kept].sort_values("run_id").reset_index(drop=True)


def test_the_sweep_file_expands_to_every_combination_with_stable_distinct_run_ids(tmp_path):
    spec = load_sweep(_sweep_file(tmp_path, SWEEP + "variants: {loose: {slam: {loop_closure: {min_score: 0.3}}}}\n"
                                  "robustness: {runs: 3, seed: 5}\n"))
    runs = spec.runs()
    assert len(runs) == 2 * 2 * 2 * 1 + 3  # scenes × seeds × SNRs × variants, then the generated cases
    assert len({r.run_id for r in runs}) == len(runs)
    assert [r.run_id for r in runs] == [r.run_id for r in load_sweep(tmp_path / "sweep.yaml").runs()]
    generated = runs[-3:]
    assert all(r.labels["motion"] and r.labels["room"] for r in generated)
    assert len({(r.seed, r.snr_db) for r in generated}) == 3  # each case its own seed and SNR
    assert runs[0].overrides["slam"] == {"loop_closure": {"min_score": 0.3}}


@pytest.mark.parametrize("text, field", [
    ("seeds: [1]\n", "scenes"),
    ("scenes: [paper-cnv]\nslam: {front_end: {window_m: -1}}\n", "slam.front_end.window_m"),
    ("scenes: [paper-cnv]\nvariants: {bad: {radio: {n_subcarriers: 3}}}\n", "variants.bad.radio.n_subcarriers"),
    ("scenes: [paper-cnv]\nsnr_db: [ten]\n", "snr_db.0"),
    ("scenes: paper-cnv\nunknown: 1\n", "scenes"),
])
def test_a_bad_sweep_file_is_refused_naming_the_field(tmp_path, text, field):
    with pytest.raises(SweepError) as caught:
        load_sweep(_sweep_file(tmp_path, text))
    assert caught.value.field == field
    done = subprocess.run([sys.executable, "-m", "radioslam.cli", "sweep", str(tmp_path / "sweep.yaml"), "--out",
                           str(tmp_path / "out"), "--scheduler", "synchronous"], capture_output=True, text=True)
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1 and field in done.stderr
    assert not (tmp_path / "out").exists()


def test_a_synchronous_sweep_writes_the_tidy_table_and_resumes(tmp_path):
    """8 runs: 4 of a one-plate scene (ATE 0 with one pose; the plate's range within 1 cm), 4 of a scene
    that does not exist (rows with the error naming it, not a crash). results.parquet and results.csv hold
    the same table, ★ columns first and every key of a run's metrics.json after. Run again: nothing runs;
    with one row file removed: that run alone."""
    out = tmp_path / "out"
    first = run_sweep(load_sweep(_sweep_file(tmp_path)), out, scheduler="synchronous")
    table = first.table
    assert first.ran == 8 and first.skipped == 0 and first.failed == 4
    assert list(table.columns[:5]) == STAR_COLUMNS
    ok = table[table["status"] == "ok"]
    assert sorted(zip(ok["seed"], ok["snr_db"])) == [(1, 10.0), (1, 20.0), (2, 10.0), (2, 20.0)]
    metrics = json.loads((out / "runs" / ok["run_id"].iloc[0] / "metrics.json").read_text())
    flat = {k for k, v in metrics.items() if not isinstance(v, dict)} | \
        {f"{k}.{sub}" for k, v in metrics.items() if isinstance(v, dict) for sub in v}
    assert flat <= set(table.columns) and "ate_rmse_m" in flat and "status_counts.matched" in flat
    failed = table[table["status"] == "failed"]
    assert (failed["scene"] == "no-such-scene").all() and failed["error"].str.contains("no-such-scene").all()
    assert ok["error"].fillna("").eq("").all()
    parquet, csv = pd.read_parquet(out / "results.parquet"), pd.read_csv(out / "results.csv")
    assert list(parquet.columns) == list(csv.columns) == list(table.columns)
    assert np.allclose(parquet["ate_rmse_m"].astype(float), csv["ate_rmse_m"].astype(float), equal_nan=True)
    assert (out / "ate_vs_snr.png").stat().st_size > 0
    again = run_sweep(load_sweep(tmp_path / "sweep.yaml"), out, scheduler="synchronous")
    assert again.ran == 0 and again.skipped == 8
    pd.testing.assert_frame_equal(_deterministic(again.table), _deterministic(table))
    (out / "rows" / f"{ok['run_id'].iloc[0]}.json").unlink()
    resumed = run_sweep(load_sweep(tmp_path / "sweep.yaml"), out, scheduler="synchronous")
    assert resumed.ran == 1 and resumed.skipped == 7
    retried = run_sweep(load_sweep(tmp_path / "sweep.yaml"), out, scheduler="synchronous", retry_failed=True)
    assert retried.ran == 4


def test_a_local_cluster_of_two_workers_gives_the_synchronous_rows(tmp_path):
    """The same tasks on a dask.distributed LocalCluster of 2 worker processes, on a running cluster given
    by its address, and on the synchronous scheduler: the same rows (timings aside), whatever order they
    finished in."""
    spec = load_sweep(_sweep_file(tmp_path, "scenes: [single-plate:3, single-plate:5]\nseeds: [1, 2]\n"))
    from dask.distributed import LocalCluster

    cluster = run_sweep(spec, tmp_path / "cluster", workers=2)
    synchronous = run_sweep(spec, tmp_path / "sync", scheduler="synchronous")
    assert cluster.ran == synchronous.ran == 4 and cluster.failed == 0
    pd.testing.assert_frame_equal(_deterministic(cluster.table), _deterministic(synchronous.table))
    with LocalCluster(n_workers=1, threads_per_worker=1, dashboard_address=None) as running:
        assert running.scheduler_address.startswith("tcp://")
        remote = run_sweep(spec, tmp_path / "remote", scheduler=running.scheduler_address)  # --scheduler tcp://…
    pd.testing.assert_frame_equal(_deterministic(remote.table), _deterministic(synchronous.table))


def test_success_by_motion_class_is_drawn_from_generated_rows(tmp_path):
    from radioslam.viz.sweep_figures import sweep_figures

    table = pd.DataFrame({"scene": ["a", "b", "c"], "seed": [1, 2, 3], "snr_db": [10.0, 10.0, 10.0],
                          "status": ["ok", "ok", "failed"], "error": ["", "", "boom"], "variant": ["", "", ""],
                          "motion": ["smooth", "sharp", "sharp"], "ate_rmse_m": [0.01, 0.5, np.nan]})
    drawn = sweep_figures(table, tmp_path)
    assert [p.name for p in drawn] == ["success_by_motion.png"]  # one SNR: no ATE-against-SNR plot
