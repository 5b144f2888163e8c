"""The motion prior (issue #47): the probability of a step for the platform that carries the terminal,
fused with odometry when it is given.

A step s = (x, y, θ) in the previous pose's frame has the density

    p(s) = (1 − ε − ε_J) · Σ_h w_h N(s; μ_h, Σ_h) + ε · U_W(s) + ε_J · U_A(s),

a Gaussian mixture over what the platform does next (hypotheses h of :mod:`radioslam.slam.motion`:
the odometry's step, the last step repeated, standing still, the last turn repeated on the spot) and
two heavy-tailed shares of the unexpected, each its own event: ε, a slip or a sudden turn, uniform over
every step the front end searches (U_W: any heading, a translation within ±``max_step_m`` in x and y,
branch and bound's square window), and ε_J, the terminal carried beyond that (a kidnap), uniform over the
area a wider search covers (U_A: a relocalization's, the map's; none where no area is given). A half turn
in one step is thus always possible, never free: it costs log((1 − ε − ε_J) N_peak / (ε U_W)) against a
step the model expects (a robust prior in the sense of Olson & Agarwal's max-mixtures, RSS 2012); a jump
to a look-alike place far away costs ε / ε_J more than a surprise within reach, which a fold onto mapped
space must pay for with its scans.

- Without odometry the Gaussians' widths are the platform's (:class:`Platform`): how much a step may
  differ from the last one.
- With full odometry the mixture is the odometry's step alone, at its stated noise.
- With rotation-only odometry (a gyro: the turn measured, the translation unknown) each hypothesis
  keeps its translation at the platform's width and takes the gyro's turn at the gyro's noise.

Every value here is a probability or a physical quantity per step; ``log_prob`` is a density over
ℝ² × (−π, π] (up to the Gaussians' mass beyond ±π), the unexpected's share over the searched window only.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

import numpy as np

from radioslam.slam.se2 import wrap_angle


class Platform(str, Enum):
    """What carries the terminal: how far one step may differ from the motion before it."""

    ROBOT = "robot"  # a wheeled robot: smooth speed, turns of tens of degrees a step, little sideways
    HANDHELD = "handheld"  # a person's hand: sways, stops, turns on the spot
    UNKNOWN = "unknown"  # anything: broad, and a large share of the unexpected


@dataclass(frozen=True)
class PlatformModel:
    """Per-step standard deviations of a step about its hypothesis, and the unexpected's share ε."""

    along_m: float  # along the direction of travel (speeding up, slowing down)
    across_m: float  # sideways
    turn_rad: float  # the turn's change from the hypothesis' turn
    surprise: float  # ε: the share of steps within a step's reach the Gaussians do not describe (slips, sudden turns)
    jump: float  # the share of steps that carry the terminal beyond a step's reach (a kidnap)


# widths per scan at walking pace (0.3–1 m a scan). A robot holds its course: its speed changes by a
# decimetre a scan and it turns with its path (the shared buildings' tours: ≤ 60° at a corner, 4σ: the
# tail's 0.1 % takes the sharpest). A person sways a hand-width and turns 30° a scan. Anything else (the
# default; the generated suite's motions: corners turned in one scan, heading held while the path turns,
# 30° turns on the spot and U-turns in one scan, 1–2 % of its steps turning more than 90°): half a metre
# either way (a walk's direction may change by a right angle in one scan), 45° (a quarter turn costs 2
# nats, e² ≈ 7 : 1, within the odds a scan can overturn), and 2 % of steps unexpected (a half turn: ≈ 7
# nats). A kidnap (the terminal carried beyond a step) is rarer by orders of magnitude than a sudden turn for
# every platform: one scan in 10⁴ (a robot's, driven, one in 10⁵), 200 : 1 against it beyond the sudden turn's
# share, past the ending's odds, so that a jump's prior is not a turn's.
PLATFORMS = {
    Platform.ROBOT: PlatformModel(along_m=0.1, across_m=0.05, turn_rad=np.radians(15.0), surprise=1e-3, jump=1e-5),
    Platform.HANDHELD: PlatformModel(along_m=0.25, across_m=0.15, turn_rad=np.radians(30.0), surprise=1e-2,
                                     jump=1e-4),
    Platform.UNKNOWN: PlatformModel(along_m=0.5, across_m=0.5, turn_rad=np.radians(45.0), surprise=2e-2, jump=1e-4),
}


@dataclass(frozen=True)
class MotionPrior:
    """The step density for one scan: Gaussian components (means (H, 3), sds (H, 3), weights (H,)) in
    the previous pose's frame, the unexpected's shares (within the searched window, and a kidnap's beyond it)
    and the window's half width."""

    means: np.ndarray
    sigmas: np.ndarray
    weights: np.ndarray
    surprise: float
    max_step_m: float
    jump: float  # the kidnap's share (beyond the window)

    @classmethod
    def of(cls, hypotheses: np.ndarray, platform: PlatformModel, max_step_m: float,
           odometry_sigmas: np.ndarray | None = None, gyro: tuple[float, float] | None = None,
           pace_known: bool = True) -> "MotionPrior":
        """The prior around the step ``hypotheses`` (H, 3) (odometry's first when ``odometry_sigmas``, its
        per-step sds (3,), are given: then it alone); ``gyro`` (turn, sd): a measured turn with no
        translation, replacing every hypothesis' turn. Without a known pace (the walk's first step, or the
        first after a jump: no last step to repeat) the translation is any step's: half ``max_step_m``
        either way."""
        hypotheses = np.atleast_2d(np.asarray(hypotheses, dtype=np.float64))
        if odometry_sigmas is not None:
            means, sigmas = hypotheses[:1], np.atleast_2d(odometry_sigmas).astype(np.float64)
        else:
            means = hypotheses.copy()
            along, across = (platform.along_m, platform.across_m) if pace_known else (max_step_m / 2,) * 2
            sigmas = np.tile([along, across, platform.turn_rad], (len(means), 1))
        if gyro is not None:
            means, sigmas = means.copy(), sigmas.copy()
            means[:, 2], sigmas[:, 2] = gyro[0], gyro[1]
        weights = np.full(len(means), 1.0 / len(means))
        return cls(means, sigmas, weights, platform.surprise, max_step_m, platform.jump)

    def log_prob(self, steps: np.ndarray, area_m2: float | None = None) -> np.ndarray:
        """log p(s) (C,) of steps (C, 3) in the previous pose's frame (x forward, y left, θ); the unexpected share
        uniform over the front end's window, and beyond it (a jump) over ``area_m2`` (the area a wider search
        covers: a relocalization's, the map's), or impossible where none is given."""
        steps = np.atleast_2d(np.asarray(steps, dtype=np.float64))
        d = steps[:, None, :] - self.means[None]
        d[..., 2] = wrap_angle(d[..., 2])
        # the hypothesis' translation frame: along and across its own direction of travel (a standing
        # hypothesis: along the pose's heading)
        travel = np.arctan2(self.means[:, 1], self.means[:, 0])
        travel = np.where(np.hypot(self.means[:, 0], self.means[:, 1]) > 1e-9, travel, 0.0)
        c, s = np.cos(travel), np.sin(travel)
        along, across = c * d[..., 0] + s * d[..., 1], -s * d[..., 0] + c * d[..., 1]
        z2 = (along / self.sigmas[:, 0]) ** 2 + (across / self.sigmas[:, 1]) ** 2 + (d[..., 2] / self.sigmas[:, 2]) ** 2
        log_norm = -1.5 * np.log(2 * np.pi) - np.sum(np.log(self.sigmas), axis=1)
        gauss = np.log(self.weights) + log_norm - 0.5 * z2  # (C, H)
        peak = gauss.max(axis=1, keepdims=True)
        mixture = peak[:, 0] + np.log(np.sum(np.exp(gauss - peak), axis=1))
        inside = np.all(np.abs(steps[:, :2]) <= self.max_step_m, axis=1)  # the searched window
        beyond = -np.inf if area_m2 is None else \
            np.log(self.jump) - np.log(max(area_m2, (2 * self.max_step_m) ** 2) * 2 * np.pi)
        unexpected = np.where(inside, np.log(self.surprise) - np.log((2 * self.max_step_m) ** 2 * 2 * np.pi), beyond)
        return np.logaddexp(np.log1p(-self.surprise - self.jump) + mixture, unexpected)
