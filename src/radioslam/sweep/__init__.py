"""Monte Carlo sweeps on Dask (issue #14): ``radioslam sweep SWEEP.yaml --out DIR`` runs every
combination of scenes, seeds, SNRs and overrides as an independent whole run (simulate, sense,
SLAM, evaluate) and gathers one tidy table, ``results.parquet`` and ``results.csv``, with plots."""

from radioslam.sweep.runner import SweepResult, run_sweep
from radioslam.sweep.spec import RunSpec, SweepError, SweepSpec, load_sweep

__all__ = ["RunSpec", "SweepError", "SweepResult", "SweepSpec", "load_sweep", "run_sweep"]
