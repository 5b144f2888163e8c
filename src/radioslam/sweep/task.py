"""One run of a sweep, as a Dask task runs it on a worker: a whole run directory
(:func:`radioslam.pipeline.run_scene`) under ``DIR/runs/<run_id>``, and its row of the table. A run
that fails is a row with its error, never an exception out of the task."""

from __future__ import annotations

import json
import time
import traceback
import warnings
from pathlib import Path

from threadpoolctl import threadpool_limits

from radioslam.errors import RadioslamError
from radioslam.io.atomic import atomic_write_text
from radioslam.pipeline import RunOptions, run_scene
from radioslam.scene import load_scene, scene_to_yaml
from radioslam.sensing import SensingConfig
from radioslam.slam import SlamConfig
from radioslam.sweep.spec import RunSpec

OK, FAILED = "ok", "failed"  # ★ the status column


def flatten(doc: dict, prefix: str = "") -> dict:
    """metrics.json as columns: nested keys joined by '.', lists as JSON text."""
    out = {}
    for key, value in doc.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            out.update(flatten(value, f"{name}."))
        elif isinstance(value, list):
            out[name] = json.dumps(value)
        else:
            out[name] = value
    return out


def _scene_argument(run: RunSpec, inputs: Path) -> str:
    """What run_scene loads: the name or file as given, or a file of the scene as this run changes it
    (a generated robustness case, radio overrides), ``inputs/<run_id>.yaml`` (beside the run
    directories: a run directory holds one run's files, run.json lists them)."""
    if run.generated is None and not run.overrides["radio"]:
        return run.scene
    if run.generated is not None:
        from radioslam.scene.procedural import robustness_suite

        scene = next(c.scene for c in robustness_suite(run.generated["runs"], run.generated["seed"])
                     if c.name == run.scene)
    else:
        scene = load_scene(run.scene)
    scene = scene.with_radio(**run.overrides["radio"])
    path = inputs / f"{run.run_id}.yaml"
    atomic_write_text(path, scene_to_yaml(scene))
    return str(path)


def run_one(run: RunSpec, out: str) -> dict:
    """The run in ``out/runs/<run_id>`` (one BLAS thread: the workers are the parallelism); its row."""
    run_dir = Path(out) / "runs" / run.run_id
    row = {"scene": run.scene, "seed": run.seed, "snr_db": run.snr_db, "status": FAILED, "error": "",
           "variant": run.variant, **run.labels, "run_id": run.run_id}
    tick, caught = time.perf_counter(), []
    try:
        with threadpool_limits(1), warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            scene = _scene_argument(run, Path(out) / "inputs")
            options = RunOptions(seed=run.seed, snr_db=run.snr_db,
                                 slam=SlamConfig.model_validate(run.overrides["slam"]),
                                 sensing=SensingConfig.model_validate(run.overrides["sensing"]))
            _, metrics = run_scene(scene, run_dir, options)
        row.update(status=OK, snr_db=load_scene(str(run_dir / "scene.yaml")).radio.snr_db, **flatten(metrics))
    except RadioslamError as exc:
        row["error"] = exc.one_line()
    except Exception as exc:  # noqa: BLE001 - a failing run is a row with its error, not a crashed sweep
        where = traceback.extract_tb(exc.__traceback__)[-1]
        reason = " ".join(str(exc).split())
        row["error"] = f"{type(exc).__name__}: {reason} ({Path(where.filename).name}:{where.lineno})"
    # what numpy or matplotlib said of the run, counted; not a library's deprecation notes, which a worker
    # process meets once, at its first import (pyparsing's under matplotlib 3.9: 14 in a fresh worker)
    row["warnings"] = sum(not issubclass(w.category, (DeprecationWarning, PendingDeprecationWarning)) for w in caught)
    row["run_seconds"] = time.perf_counter() - tick
    return row
