"""The sweep's main loop (issue #14): every run of the sweep file not finished before, each an
independent Dask task (:func:`radioslam.sweep.task.run_one`); each row saved as it arrives
(``DIR/rows/<run_id>.json``: a sweep killed and run again skips what it finished), then the table
``DIR/results.parquet`` and ``DIR/results.csv`` (★ columns ``scene``, ``seed``, ``snr_db``, ``status``,
``error``, then every key of ``metrics.json``) and its plots.

Schedulers: by default a ``dask.distributed`` LocalCluster, one single-threaded worker process per
core (``workers``); ``scheduler="tcp://HOST:8786"`` uses a running cluster (whose workers must see
``DIR``); ``scheduler="synchronous"`` runs the same tasks one by one in this process (Dask's
synchronous scheduler: for debugging and tests).
"""

from __future__ import annotations

import json
import logging
import os
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import dask
import pandas as pd

from radioslam.io.atomic import atomic_path, atomic_write_text
from radioslam.io.json_io import dumps
from radioslam.sweep.spec import RunSpec, SweepError, SweepSpec
from radioslam.sweep.task import FAILED, run_one

SYNCHRONOUS = "synchronous"
LEADING = ["scene", "seed", "snr_db", "status", "error"]  # ★ the table's first columns


@dataclass
class SweepResult:
    table: pd.DataFrame  # one row per run of the sweep, finished before or now
    ran: int  # runs made by this call
    skipped: int  # runs finished by an earlier call
    seconds: float

    @property
    def failed(self) -> int:
        return int((self.table["status"] == FAILED).sum())


def run_sweep(spec: SweepSpec, out: Path, scheduler: str | None = None, workers: int | None = None,
              retry_failed: bool = False, on_row: Callable[[dict, int, int], None] | None = None) -> SweepResult:
    """Every run of ``spec`` under ``out``; ``on_row(row, done, total)`` as each finishes."""
    tick, out = time.perf_counter(), Path(out)
    runs = spec.runs()
    finished = _finished(out, runs, retry_failed)
    todo = [run for run in runs if run.run_id not in finished]
    for done, row in enumerate(_execute(todo, out, scheduler, workers), start=1):
        atomic_write_text(_row_file(out, row["run_id"]), dumps(row) + "\n")
        finished[row["run_id"]] = row
        if on_row is not None:
            on_row(row, done, len(todo))
    table = tidy([finished[run.run_id] for run in runs])
    write_table(table, out)
    from radioslam.viz.sweep_figures import sweep_figures

    sweep_figures(table, out)
    return SweepResult(table, len(todo), len(runs) - len(todo), time.perf_counter() - tick)


def _row_file(out: Path, run_id: str) -> Path:
    return out / "rows" / f"{run_id}.json"


def _finished(out: Path, runs: list[RunSpec], retry_failed: bool) -> dict[str, dict]:
    """The rows of the runs finished by an earlier call (a failed one too, unless ``retry_failed``)."""
    rows = {}
    for run in runs:
        path = _row_file(out, run.run_id)
        try:
            row = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            continue
        if not (retry_failed and row.get("status") == FAILED):
            rows[run.run_id] = row
    return rows


def _execute(runs: list[RunSpec], out: Path, scheduler: str | None, workers: int | None) -> Iterator[dict]:
    """The rows of ``runs``, each one's as soon as it finishes."""
    if not runs:
        return
    tasks = [dask.delayed(run_one, pure=False)(run, str(out)) for run in runs]
    if scheduler == SYNCHRONOUS:
        for task in tasks:
            yield dask.compute(task, scheduler=SYNCHRONOUS)[0]
        return
    from dask.distributed import Client, LocalCluster, as_completed

    cluster = None if scheduler else LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1,
                                                  processes=True, dashboard_address=None,
                                                  silence_logs=logging.ERROR)
    try:
        try:
            client = Client(scheduler or cluster)
        except OSError as exc:  # no scheduler there (dask's timeout names no file): one line naming the address
            raise SweepError(f"cannot reach the Dask scheduler: {exc}", file=scheduler or "LocalCluster",
                             field="--scheduler") from None
        with client:
            for future in as_completed(client.compute(tasks)):
                yield future.result()
    finally:
        if cluster is not None:
            cluster.close()


def tidy(rows: list[dict]) -> pd.DataFrame:
    """One row per run; the ★ columns first, the rest in the order they first appear."""
    table = pd.DataFrame(rows)
    for column in LEADING:
        if column not in table:
            table[column] = pd.Series(dtype=object)
    return table[LEADING + [c for c in table.columns if c not in LEADING]]


def write_table(table: pd.DataFrame, out: Path) -> None:
    """results.parquet and results.csv, each written whole or not at all."""
    with atomic_path(out / "results.parquet") as tmp:
        table.to_parquet(tmp, index=False)
    with atomic_path(out / "results.csv") as tmp:
        table.to_csv(tmp, index=False)
