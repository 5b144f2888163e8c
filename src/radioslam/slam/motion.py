"""The motion model (issue #12): where the terminal may be at the next scan, as hypotheses.

A walker turns on the spot, repeats a turn or goes straight on, so no single prediction is
the centre of the search: each hypothesis below seeds the front end's search (its heading
is searched like a rotation candidate of the scan itself), and the front end picks by the
scans. The primary hypothesis (external odometry where given, else constant velocity, else
standing still) breaks ties between candidates the scans cannot tell apart, and is the pose
of a scan that cannot be matched.

Along a direction no wall fixes (a featureless corridor) the step is the walker's pace: the
median length of the latest straight steps that observed every direction, along the
predicted direction of travel. One step's speed is a poor guess for many steps.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum

import numpy as np

from radioslam.slam.config import MotionConfig
from radioslam.slam.motion_prior import PLATFORMS, MotionPrior, Platform, PlatformModel
from radioslam.slam.se2 import between, compose, pose_covariance, wrap_angle


class MotionHypothesis(str, Enum):
    ODOMETRY = "odometry"  # the external odometry's step (wheels, IMU)
    CONSTANT_VELOCITY = "constant-velocity"  # the last step repeated
    STILL = "still"  # standing still
    TURN_ON_THE_SPOT = "turn-on-the-spot"  # the last turn repeated without moving


@dataclass(frozen=True)
class Hypothesis:
    kind: MotionHypothesis
    pose: np.ndarray


@dataclass
class MotionModel:
    """Built from the ``motion`` config section (:meth:`from_config`); ``odometry`` (P, 3) are external
    odometry poses in their own frame (their steps are what counts), or None; a gyro's odometry has NaN
    positions (its turns alone are measured)."""

    pace_scans: int
    straight_rad: float
    odometry: np.ndarray | None = None
    velocity: np.ndarray | None = None  # the last step, None before two poses or after a jump
    speeds: list[float] = field(default_factory=list)  # lengths of observed straight steps
    platform: PlatformModel = PLATFORMS[Platform.UNKNOWN]
    max_step_m: float = 1.3
    odometry_sigmas: np.ndarray = field(default_factory=lambda: np.array([0.05, 0.05, np.radians(2.0)]))

    @classmethod
    def from_config(cls, cfg: MotionConfig, odometry: np.ndarray | None = None) -> "MotionModel":
        sigmas = np.array([cfg.odometry_sigma_m, cfg.odometry_sigma_m, np.radians(cfg.odometry_sigma_deg)])
        return cls(cfg.pace_scans, np.radians(cfg.straight_deg), odometry, platform=PLATFORMS[cfg.platform],
                   max_step_m=cfg.max_step_m, odometry_sigmas=sigmas)

    @property
    def gyro_only(self) -> bool:
        """The odometry measures turns only (its positions are NaN)."""
        return self.odometry is not None and bool(np.isnan(self.odometry[:, :2]).all())

    def dead_reckoning_scans(self) -> int:
        """How many steps the full odometry alone carries a pose before its drift leaves the front end's search
        window (3σ of the position > ``max_step_m``; σ² after n steps of its stated noise: n σ_m² for the
        translation, σ_θ² ℓ² n³ / 3 for the heading's random walk over steps of its median length ℓ): a stretch no
        scan fixed is lost only once it is that long. 0 without full odometry (a platform's own step is as wide
        as the window)."""
        if self.odometry is None or self.gyro_only:
            return 0
        length = np.linalg.norm(np.diff(self.odometry[:, :2], axis=0), axis=1)
        step = float(np.median(length)) if len(length) else 0.0
        n = np.arange(1, len(self.odometry) + 1, dtype=np.float64)
        sigma = np.sqrt(n * self.odometry_sigmas[0] ** 2 + self.odometry_sigmas[2] ** 2 * step ** 2 * n ** 3 / 3)
        beyond = np.flatnonzero(3 * sigma > self.max_step_m)
        return int(n[beyond[0]]) if len(beyond) else len(self.odometry) + 1

    def odometry_step(self, k: int) -> np.ndarray | None:
        """The external odometry's step from pose k − 1 to k (x, y NaN for a gyro), or None."""
        if self.odometry is None or k < 1 or k >= len(self.odometry):
            return None
        if self.gyro_only:
            return np.array([np.nan, np.nan, wrap_angle(self.odometry[k, 2] - self.odometry[k - 1, 2])])
        return between(self.odometry[k - 1], self.odometry[k])

    def prior(self, k: int, last: np.ndarray) -> MotionPrior:
        """The motion prior of step k (:mod:`radioslam.slam.motion_prior`): around the odometry's step at its
        noise, or around every hypothesis at the platform's widths (a gyro's turn at its noise)."""
        steps = np.array([between(last, h.pose) for h in self.hypotheses(k, last)])
        step = self.odometry_step(k)
        if step is not None and not self.gyro_only:
            return MotionPrior.of(steps, self.platform, self.max_step_m, self.odometry_sigmas)
        gyro = None if step is None else (float(step[2]), float(self.odometry_sigmas[2]))
        return MotionPrior.of(steps, self.platform, self.max_step_m, gyro=gyro, pace_known=self.velocity is not None)

    def log_prob(self, k: int, last: np.ndarray, poses: np.ndarray, area_m2: float | None = None) -> np.ndarray:
        """log p(pose k | pose k − 1 at ``last``) (C,) at ``poses`` (C, 3): the step's prior (:meth:`prior`), its
        unexpected share beyond the front end's window spread over ``area_m2`` (:meth:`MotionPrior.log_prob`)."""
        return self.prior(k, last).log_prob(between(last, np.atleast_2d(poses)), area_m2)

    def hypotheses(self, k: int, last: np.ndarray) -> list[Hypothesis]:
        """Where pose k may be, given pose k − 1 at ``last``; the primary hypothesis first."""
        out = []
        step = self.odometry_step(k)
        if step is not None and self.gyro_only:  # the gyro's turn, standing: the primary where the scans fail
            step = np.array([0.0, 0.0, step[2]]) if self.velocity is None else \
                np.array([self.velocity[0], self.velocity[1], step[2]])
        if step is not None:
            out.append(Hypothesis(MotionHypothesis.ODOMETRY, compose(last, step)))
        if self.velocity is not None:
            out.append(Hypothesis(MotionHypothesis.CONSTANT_VELOCITY, compose(last, self.velocity)))
            turn = np.array([0.0, 0.0, self.velocity[2]])
            out.append(Hypothesis(MotionHypothesis.TURN_ON_THE_SPOT, compose(last, turn)))
        out.append(Hypothesis(MotionHypothesis.STILL, np.asarray(last, dtype=np.float64).copy()))
        return out

    def predict(self, k: int, last: np.ndarray) -> np.ndarray:
        """The primary hypothesis' pose."""
        return self.hypotheses(k, last)[0].pose

    def paced(self, prediction: np.ndarray, last: np.ndarray) -> np.ndarray:
        """``prediction`` moved along its own direction of travel so that the step is the pace,
        when the predicted step goes straight; else unchanged (turning on the spot stays put)."""
        straight = abs(between(last, prediction)[2]) < self.straight_rad
        return pace_prediction(prediction, last, self.speeds if straight else [], self.pace_scans)

    def update(self, step: np.ndarray | None, observed: bool) -> None:
        """Record the step just made (None: a jump, e.g. a relocalization, leaves no velocity);
        ``observed``: the scans fixed every direction of it, so it counts towards the pace."""
        self.velocity = None if step is None else np.asarray(step, dtype=np.float64)
        if step is not None and observed and abs(step[2]) < self.straight_rad:
            self.speeds.append(float(np.linalg.norm(step[:2])))


def jump_covariance(cfg: MotionConfig) -> np.ndarray:
    """The covariance of a step the front end did not see (a relocalization, a kidnap, a branch
    left): next to no information, isotropic in position (the same in every frame)."""
    return pose_covariance(cfg.relocalized_sigma_m, cfg.relocalized_sigma_deg)


def pace_prediction(prediction: np.ndarray, last: np.ndarray, speeds: list[float], scans: int) -> np.ndarray:
    """``prediction`` moved along its own direction of travel from ``last`` so that the step is
    the median of the last ``scans`` observed step lengths ``speeds``: the walker's pace."""
    travel = prediction[:2] - last[:2]
    length = float(np.linalg.norm(travel))
    if not speeds or length < 1e-9:
        return prediction
    paced = prediction.copy()
    paced[:2] = last[:2] + travel * (float(np.median(speeds[-scans:])) / length)
    return paced
