"""The SLAM benchmark's cases (issue #47): what ``bench_robustness.py`` runs.

Four families, each a list of :class:`BenchCase`:

- ``room``: the generated rooms and motions of issue #12 (``scene.procedural.robustness_suite``);
- ``lookalike``: rooms alike under a half turn, a quarter turn or a mirror, with and without one
  asymmetric feature, walked as figure eights, clovers and loops (``scene.lookalike``);
- ``office``: rooms on both sides of a corridor 1.3–2.5 m wide, toured through their doors
  (``scene.offices``), poses down to 0.5 m from a wall;
- ``building``: the real floor plans of ``../shared/buildings/`` (read from there, never copied),
  radio only and with their wheeled robot's odometry (the scene's ``odometry:`` block, drawn from
  the run's seed as ``radioslam run --odometry simulated`` does).

A case succeeds when its ATE is ≤ 0.2 m (rooms, look-alikes, offices), ≤ 0.5 m in a building without
odometry, and with odometry ≤ 0.5 m and ≤ a third of the odometry's own ATE.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from radioslam.eval.trajectory_metrics import ate_rmse
from radioslam.scene import Scene, load_scene
from radioslam.scene.lookalike import lookalike_suite
from radioslam.scene.offices import office_suite
from radioslam.scene.procedural import robustness_suite
from radioslam.sim.odometry import odometry_rng, simulated_odometry

BUILDINGS = Path(__file__).resolve().parents[2] / "shared" / "buildings"
SMALL_BUILDINGS = ("aws_small_house", "aws_small_warehouse")  # the --quick subset's buildings
ROOM_SUCCESS_M, BUILDING_SUCCESS_M, ODOMETRY_SHARE = 0.2, 0.5, 1 / 3
CONFIDENT_M = 0.5  # a run this far off with neither flag set is a confident failure


@dataclass(frozen=True)
class BenchCase:
    """One benchmark run: a scene, the seed its scans are simulated with, and the odometry given."""

    name: str
    family: str  # room, lookalike, office, building
    room: str
    motion: str
    scene: Scene
    seed: int
    snr_db: float
    with_odometry: bool = False

    def odometry(self) -> np.ndarray | None:
        """The external odometry the SLAM is given (the scene's drifting odometry of this seed), or None."""
        if not self.with_odometry:
            return None
        return simulated_odometry(self.scene.poses, self.scene.spec.odometry, odometry_rng(self.seed))

    def succeeded(self, ate_m: float, odometry_ate_m: float | None) -> bool:
        if self.family != "building":
            return ate_m <= ROOM_SUCCESS_M
        if odometry_ate_m is None:
            return ate_m <= BUILDING_SUCCESS_M
        return ate_m <= BUILDING_SUCCESS_M and ate_m <= ODOMETRY_SHARE * odometry_ate_m

    def odometry_ate(self) -> float | None:
        odometry = self.odometry()
        return None if odometry is None else ate_rmse(odometry, self.scene.poses)


def _generated(cases, family: str) -> list[BenchCase]:
    return [BenchCase(c.name, family, c.room.value, c.motion.value, c.scene, c.seed, c.snr_db) for c in cases]


def building_cases(names: list[str] | None = None, seed: int = 1) -> list[BenchCase]:
    """The shared buildings (all, or ``names``), each radio only and with its odometry; none when the
    folder is not beside the checkout."""
    if not BUILDINGS.is_dir():
        return []
    out = []
    for folder in sorted(p for p in BUILDINGS.iterdir() if (p / "scene.yaml").is_file()):
        if names is not None and folder.name not in names:
            continue
        scene = load_scene(str(folder / "scene.yaml"))
        for with_odometry in (False, True):
            name = f"{folder.name}{'+odometry' if with_odometry else ''}"
            out.append(BenchCase(name, "building", folder.name, "tour", scene, seed, scene.radio.snr_db,
                                 with_odometry))
    return out


def benchmark_suite(seed: int = 0, quick: bool = False, building_seed: int = 1) -> list[BenchCase]:
    """120 runs (48 rooms, 30 look-alikes, 30 offices, 6 buildings × 2); ``quick``: every fourth generated
    case and the two smallest buildings (31 runs)."""
    generated = _generated(robustness_suite(48, seed), "room") + \
        _generated(lookalike_suite(30, seed), "lookalike") + _generated(office_suite(30, seed), "office")
    if quick:
        return generated[::4] + building_cases(list(SMALL_BUILDINGS), building_seed)
    return generated + building_cases(None, building_seed)
