"""SLAM settings (paper §IV-B), one section per component (issue #12). Lengths in metres, angles
in degrees at this interface only. Loadable from the ``slam:`` section of a YAML config file
(:func:`load_slam_config`); every tuning constant of the SLAM lives here, none in the code. ``docs/settings.md``
lists them in one table (default, unit, what each rests on); change both together.
"""

from __future__ import annotations

from enum import Enum
from pathlib import Path

from pydantic import BaseModel, ConfigDict, Field

from radioslam.config_file import load_section
from radioslam.slam.errors import SlamError
from radioslam.slam.motion_prior import Platform


class _Section(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class GridConfig(_Section):
    """The likelihood field every matcher scores against (Olson 2009 §III)."""

    resolution_m: float = Field(0.05, ge=0.005, le=1.0)
    # point likelihood exp(−d²/2σ²): radio points sit 1–7 cm off their wall (range error ≈ mm,
    # the beam direction quantized to the codebook); σ also absorbs submap blur
    sigma_m: float = Field(0.05, gt=0, le=2.0)
    # specular normals agree to ±σ_ψ (arc peaks locate a wall normal to ~0.1°; the coarse search steps 0.5°)
    normal_sigma_deg: float = Field(1.0, gt=0)
    # points with a normal are scored point-to-plane within this distance of the nearest map point
    plane_reach_m: float = Field(1.5, ge=0, le=10.0)
    # negative evidence (:mod:`radioslam.slam.free_space`): a point on a cell the map's scans saw
    # through (each arc's normal line up to free_stop_m short of its foot, a disc around each pose)
    # scores −free_penalty instead of 0
    free_penalty: float = Field(1.0, ge=0)
    free_stop_m: float = Field(0.3, ge=0, le=10.0)
    free_pose_radius_m: float = Field(0.5, ge=0, le=10.0)
    # max-pooled pyramid levels of branch and bound: the coarsest cell is 2^levels cells wide
    branch_levels: int = Field(4, ge=1, le=8)


class ScanConfig(_Section):
    """How a radio scan becomes matchable points (:mod:`radioslam.slam.normals`)."""

    min_points: int = Field(8, ge=3)  # a scan with fewer points is skipped with a warning
    # bounded memory whatever the input (:mod:`radioslam.slam.thinning`): points beyond max_range_m are
    # dropped, and a scan of more than max_points is thinned to its strongest point per grid cell, then
    # to its max_points strongest (a radio scan holds a few hundred at most)
    max_points: int = Field(1024, ge=16, le=1_000_000)
    max_range_m: float = Field(100.0, gt=0, le=10_000.0)
    arc_range_m: float = Field(0.10, gt=0)  # consecutive beams within this range form one arc
    # an arc peaking on its sector's edge joins the adjacent orientation's arc at its range whose peak
    # lies within this bearing (a wall between two sectors)
    seam_gap_deg: float = Field(8.0, gt=0)
    # degeneracy (Zhang et al. 2016): line fits through neighbours within this radius where no
    # specular normal is known; a point within this many σ of the map agrees with it
    neighbour_radius_m: float = Field(0.5, gt=0)
    neighbours: int = Field(6, ge=3)
    inlier_sigmas: float = Field(2.0, gt=0)


class FrontEndConfig(_Section):
    """Scan-to-local-map matching (:mod:`radioslam.slam.front_end`)."""

    local_map_scans: int = Field(10, ge=1, le=1000)  # the front end matches against this many latest scans
    # and against up to this many older scans taken within nearby_radius_m of the last pose
    nearby_scans: int = Field(20, ge=0, le=1000)
    nearby_radius_m: float = Field(3.0, ge=0, le=100.0)
    # the response surface (covariance, Olson 2009 §IV) and the final search: ±window around the
    # winner of the wide search (loop closures use twice this window: their winner is coarser)
    window_m: float = Field(0.15, gt=0, le=5.0)
    window_deg: float = Field(3.0, gt=0)
    angle_step_deg: float = Field(0.5, gt=0)
    # global rotation search: normal-bearing histograms of scan and local map, circularly correlated
    histogram_bin_deg: float = Field(1.0, gt=0)
    histogram_smooth_deg: float = Field(2.0, gt=0)
    rotation_candidates: int = Field(6, ge=1, le=64)  # strongest correlation peaks kept
    rotation_window_deg: float = Field(2.0, gt=0)  # searched around each candidate and hypothesis
    # a candidate's score is discounted by this fraction times its turn from the nearest motion
    # hypothesis' heading in half turns (a 180° surprise loses it all): the motion prior
    motion_prior: float = Field(0.25, ge=0, lt=1)
    # and, once a step is predicted, by this fraction times its distance from the predicted position
    # per max_step_m (capped at 1)
    translation_prior: float = Field(0.2, ge=0, lt=1)
    # two distinct candidates whose discounted scores differ by less than this fraction are ambiguous
    ambiguity_margin: float = Field(0.08, ge=0, lt=1)
    # branch and bound scores on the 5 cm lattice, where a point may sit a cell from its wall (a
    # loss of up to e^(-1/2) per point): it keeps candidates this much further below the best, and up
    # to refined_candidates of them are refined and scored off the lattice before any decision
    lattice_allowance: float = Field(0.15, ge=0, lt=1)
    refined_candidates: int = Field(4, ge=1, le=64)
    # candidates nearer than this in position and heading are one hypothesis (non-maximum suppression)
    distinct_m: float = Field(0.3, gt=0)
    distinct_deg: float = Field(6.0, gt=0)
    # a match scored below min_match_score is not trusted; between it and min + trust_ramp its
    # weight against the prediction grows smoothly from 0 to 1 (no cliff at the threshold)
    min_match_score: float = Field(0.25, ge=0, le=1)
    trust_ramp: float = Field(0.10, gt=0)
    # a match is degenerate when its surfaces' information (Σ n nᵀ) or its covariance is this
    # elongated (ratio of standard deviations): a direction nothing fixes
    degenerate_ratio: float = Field(4.0, gt=1)
    # added to every front-end covariance: the response surface treats the points as independent
    # and is over-confident; these are the step errors measured against the truth on paper-cnv
    # (sd 1.5–2.3 cm and 0.3° per scan, seeds 1–5)
    floor_sigma_m: float = Field(0.02, ge=0)
    floor_sigma_deg: float = Field(0.3, ge=0)


class MotionConfig(_Section):
    """The motion model (:mod:`radioslam.slam.motion`) and its prior (:mod:`radioslam.slam.motion_prior`)."""

    # what carries the terminal: the widths of a step about the motion's hypotheses and the share of the
    # unexpected (motion_prior.PLATFORMS)
    platform: Platform = Platform.UNKNOWN

    # the translation search covers this far from the last pose whatever the turn (steps up to 1 m)
    max_step_m: float = Field(1.3, gt=0, le=20.0)
    # along a weak direction the step is the median length of this many latest straight steps that
    # observed every direction (the walker's pace), not the last step
    pace_scans: int = Field(10, ge=1)
    straight_deg: float = Field(2.0, gt=0)  # a step turning less than this walks straight: the pace applies
    # a pose the scans cannot fix (skipped, predicted) is tied to its neighbour this loosely
    predicted_sigma_m: float = Field(0.5, gt=0)
    predicted_sigma_deg: float = Field(10.0, gt=0)
    # this many consecutive scans none of which fixed one pose (predicted, skipped, degenerate, ambiguous)
    # are a lost stretch: the position along the weak direction has been dead reckoning for that many steps
    dead_reckoned_scans: int = Field(10, ge=1)
    # a relocalized scan's jump from the pose before it: next to no information
    relocalized_sigma_m: float = Field(100.0, gt=0)
    relocalized_sigma_deg: float = Field(180.0, gt=0)
    # external odometry (--odometry FILE): per-step noise of its relative motion (between factors, the motion
    # prior, the front end's search); a run on a scene's own simulated odometry takes the scene's stated noise
    # unless these are set (:meth:`SlamConfig.with_odometry_noise`)
    odometry_sigma_m: float = Field(0.05, gt=0)
    odometry_sigma_deg: float = Field(2.0, gt=0)


class LoopClosureConfig(_Section):
    """Submaps, loop closure and relocalization (:mod:`radioslam.slam.loop_closer`)."""

    submap_scans: int = Field(7, ge=1, le=1000)  # consecutive scans per submap (MATLAB lidarSLAM's default)
    radius_m: float = Field(3.0, gt=0, le=100.0)  # candidate submaps within this distance
    # matched per scan at most (a flat cost however often a place is revisited: every lap adds its submaps
    # to the candidates): never tried ones first, then those whose matchers are kept, each group the one
    # tried longest ago first, then the nearest (Cartographer samples its candidates instead; the round robin
    # keeps every lap's submaps tied in, deterministically, and a submap whose matcher was dropped is built
    # again only when no kept or new one is near)
    loop_matches_per_scan: int = Field(3, ge=1, le=64)
    # a scan within this many scans of the last one that closed a loop (the walk tied to the map) searches
    # only every this many scans (Cartographer samples its constraint searches, a ratio of 0.3); a walk not
    # tied searches at every scan. 1: every scan searches
    tied_search_every: int = Field(3, ge=1)
    skip_submaps: int = Field(2, ge=0)  # never the most recent ones
    # a submap's matcher (its grid and branch-and-bound pyramid, in its first scan's frame) is kept until
    # one of its scans has moved this much relative to that first scan since it was built (Cartographer
    # keeps finished submaps fixed; a solution that moves them less than half a cell leaves the grid as it
    # was, a fork's switch or a cut moves them far more)
    submap_rebuild_m: float = Field(0.025, gt=0)
    submap_rebuild_deg: float = Field(0.25, gt=0)
    # at most this many submaps' matchers kept (the least recently used rebuilt when needed again): a submap's
    # grid (and pyramid) covers what its scans saw, and a radio scan sees the whole room: 8–11 MB each in
    # paper-cnv's 16 m room
    cached_matchers: int = Field(32, ge=1, le=1024)
    window_m: float = Field(1.5, gt=0, le=20.0)
    window_deg: float = Field(20.0, gt=0)
    min_score: float = Field(0.35, ge=0, le=1)  # normalized score: mean point likelihood
    # a loop's scan lies where the submap's scans saw the same walls: its arcs overlap theirs, and a
    # long point-to-plane reach (the front end's, for steps up to 1 m) would let it slide along them
    plane_reach_m: float = Field(0.5, ge=0, le=10.0)
    # a loop's weight grows smoothly from 0 at min_score to 1 at min_score + score_ramp, and falls
    # smoothly to 0 as its χ² approaches the gate (no cliff where a loop is accepted)
    score_ramp: float = Field(0.10, gt=0)
    gate_chi2: float = Field(16.27, gt=0)  # χ²(3) at 99.9 %: consistency with the graph
    # relocalization once this many consecutive scans matched nothing (one alone is a new view, such
    # as a cross aisle, and keeps the prediction): every submap, full rotation, translation over its extent
    relocalize_after: int = Field(2, ge=1)
    relocalize_min_score: float = Field(0.35, ge=0, le=1)
    relocalize_margin_m: float = Field(2.0, ge=0, le=100.0)  # beyond the map's points
    relocalize_levels: int = Field(6, ge=1, le=10)  # branch-and-bound levels for a search that wide
    # the whole map (relocalization, trials, forks) is what lies within this distance of the latest scan (a
    # square): its grid stays bounded however long the walk, ≈ (2 r / resolution)² cells at ≈ 120 B each while
    # built (0.5 GB at 50 m and 5 cm); a terminal carried farther than this from its last pose is not found again
    relocalize_radius_m: float = Field(50.0, gt=0, le=10_000.0)
    # a matched scan with this fraction of its points on known free space is searched for too, and
    # relocalized where its posterior beats its local match's (:mod:`radioslam.slam.posterior`)
    contradicted_fraction: float = Field(0.15, gt=0, le=1)
    # a matched scan scoring below suspect_drop times the median of the latest suspect_window opens a
    # trial (:mod:`radioslam.slam.lost_found`): searched for in the whole map, then followed; once
    # confirm_scans are followed and their posterior odds reach the ending's, they are relocalized
    suspect_drop: float = Field(0.7, gt=0, le=1)
    suspect_window: int = Field(10, ge=2)
    confirm_scans: int = Field(3, ge=1)
    max_trial_scans: int = Field(9, ge=1)  # a trial followed this long without a decision ends undecided
    # after a confirmed trial each of the next alert_scans scans is also searched for where the terminal was taken
    alert_scans: int = Field(10, ge=0)
    # unless the map near the front end's pose, carried to the place found, scores this fraction of
    # its own score in place: the room looks the same from both places (a symmetric room)
    self_similar: float = Field(0.1, ge=0, le=1)
    # an ambiguous scan with rivals turned from the choice is a fork (:mod:`radioslam.slam.forks`; the
    # latest fork_limit, each for fork_memory scans): a rival's branch whose best match since the fork with
    # the map from before it has weight ≥ fork_weight and scores fork_gain better than the chosen branch's
    # best match there takes the rival
    fork_memory: int = Field(15, ge=1)
    fork_limit: int = Field(3, ge=0)
    fork_weight: float = Field(0.5, gt=0, le=1)
    fork_gain: float = Field(0.25, ge=0)
    # and only once the chosen branch put this fraction of its points since the fork on space the map from
    # before it saw through (evidence against it: an exploring branch puts none there)
    fork_contradicted: float = Field(0.01, ge=0, le=1)
    # and significantly more of them than the rival's branch put there (one-sided sign test, this p-value);
    # at its square the contradiction decides alone, without a rival loop (an exploring rival closes none)
    fork_significance: float = Field(0.01, gt=0, lt=1)
    # each branch is counted where the map from before places it: its scans since the fork, together, matched
    # within ± these of where its estimates (a rival's: its jump) put them
    fork_place_m: float = Field(0.5, gt=0)
    fork_place_deg: float = Field(5.0, gt=0)


class PoseGraphConfig(_Section):
    """The pose graph (:mod:`radioslam.slam.back_end`)."""

    gnc: bool = True  # loop factors robust to false closures (GncLMOptimizer)
    prior_sigma_m: float = Field(1e-4, gt=0)
    prior_sigma_deg: float = Field(5.7e-4, gt=0)
    # a loop counts toward the poses' marginal covariances (the plane adjustment's anchors) when its χ² at
    # the solution is within this (χ²(3) at 99.9 %: GNC kept it)
    inlier_chi2: float = Field(16.27, gt=0)


class PosteriorConfig(_Section):
    """The posterior of a scan's placement (:mod:`radioslam.slam.posterior`): relocalization, the trials and
    the ending weigh placements by it."""

    # a rival branch's jump is aligned on the scans before its fork within radius_m of the scans after it
    radius_m: float = Field(5.0, gt=0, le=100.0)
    # each scan is scored against the scans before it whose poses lie within its own reach (its farthest echo:
    # any viewpoint that far may have seen the surfaces it sees), at most max_scans of them, nearest first
    max_scans: int = Field(30, ge=1, le=1000)


class EndingConfig(_Section):
    """The end-of-walk comparison of trajectories (:mod:`radioslam.slam.ending`)."""

    enabled: bool = True
    # two trajectories whose every pose agrees within these are one hypothesis: they differ by how an error
    # was spread (drift, a loop's correction), not by which place a scan was taken for (a fold, a flip, a
    # wrong loop: a corridor's width, a door's spacing, a turn beyond the front end's distinct_deg)
    same_m: float = Field(0.5, gt=0)
    same_deg: float = Field(10.0, gt=0)
    # a runner-up whose posterior odds against the answer are better than 1 : odds makes the trajectory
    # ambiguous (a probability ratio: the runner-up keeps at least 5 %)
    odds: float = Field(20.0, gt=1)
    # the decisions' alternatives weighed as whole trajectories (the issue's K ≤ 8 hypotheses): those of highest
    # screened odds over the answer; each costs a likelihood grid per scan that comes back near its fork
    hypotheses: int = Field(8, ge=0, le=1000)
    # the screening's sample: each alternative's odds estimated from at most this many of the scans whose map it
    # changes, evenly spread (a likelihood grid each), where its whole scoring costs every one of them
    screened_scans: int = Field(12, ge=1, le=1000)


class Anchors(str, Enum):
    """How loosely the plane adjustment holds each pose to the pose graph's."""

    FIXED = "fixed"  # anchor_sigma_m / anchor_sigma_deg for every pose
    MARGINAL = "marginal"  # the pose graph's marginal σ of each pose, at least those


class PlaneAdjustmentConfig(_Section):
    """The last solve (:mod:`radioslam.slam.plane_adjustment`): poses and the walls their specular
    arcs face, adjusted together."""

    enabled: bool = True
    # a sighting's noise: the arc's normal bearing and its strongest echo's range (sd 0.14–0.23° and
    # 1.2–1.7 cm on paper-cnv's four walls at the true poses, 10 dB)
    bearing_sigma_deg: float = Field(0.2, gt=0)
    range_sigma_m: float = Field(0.015, gt=0)
    # a sighting joins the nearest wall within these gates at the pose graph's poses (its errors:
    # centimetres and tenths of a degree, times the distance); a wall seen from fewer scans is left out
    gate_deg: float = Field(3.0, gt=0)
    gate_m: float = Field(0.3, gt=0)
    min_sightings: int = Field(3, ge=2)
    # Tukey's biweight of a sighting's normalized residual: 0 beyond this many σ
    robust_c: float = Field(4.685, gt=0)
    # each pose is held near the pose graph's with this sd (fixed), or with its marginal sd there, at least
    # this (marginal: tight where loops closed, growing along an open chain: a hexagon walked five sides,
    # 0.24 -> 0.04 m; but a shelf hall's aisle legs, where a shelf's double bounce passes for the outer
    # wall, slide 0.08 -> 0.12 m: see docs/notes.md, session 9), and the pose graph's steps at the front
    # end's step covariance times step_inflation² (the scans' information is in both: not counted twice)
    anchors: Anchors = Anchors.MARGINAL
    anchor_sigma_m: float = Field(0.05, gt=0)
    anchor_sigma_deg: float = Field(0.5, gt=0)
    step_inflation: float = Field(3.0, gt=0)
    # a pose the front end left to the motion model (predicted, skipped) is first placed on
    # the walls within this search (its step may be a jump the motion model did not see), then held
    # to the pose graph's this loosely, and so are the steps into and out of it
    place_search_m: float = Field(1.5, gt=0)
    place_search_deg: float = Field(180.0, gt=0)
    loose_sigma_m: float = Field(1.5, gt=0)
    loose_sigma_deg: float = Field(90.0, gt=0)
    # a degenerate pose (its position along its walls the pace's; its heading from their axis, so
    # possibly a hall's 180° twin: 1.1 m and 180° off after a kidnap) is placed within this of its
    # heading, and once placed held as loosely; 0: never
    degenerate_search_deg: float = Field(180.0, ge=0)
    iterations: int = Field(30, ge=1)


class MapConfig(_Section):
    """The occupancy grid and fused cloud written after the run (:mod:`radioslam.slam.occupancy`)."""

    resolution_m: float = Field(0.05, ge=0.005, le=1.0)
    log_odds_hit: float = 0.85  # p = 0.7
    log_odds_miss: float = -0.4  # p = 0.4
    log_odds_limit: float = Field(5.0, gt=0)
    # a ray clears free space up to this short of its echo (a beam is ~13° wide: what it saw lies
    # anywhere across it at that range), and never a cell that holds a point of any scan
    free_stop_m: float = Field(0.3, ge=0)
    margin_m: float = Field(0.5, ge=0, le=100.0)


class SlamConfig(_Section):
    """Every SLAM parameter, one section per component; factories build each from its section."""

    grid: GridConfig = Field(default_factory=GridConfig)
    scan: ScanConfig = Field(default_factory=ScanConfig)
    front_end: FrontEndConfig = Field(default_factory=FrontEndConfig)
    motion: MotionConfig = Field(default_factory=MotionConfig)
    loop_closure: LoopClosureConfig = Field(default_factory=LoopClosureConfig)
    pose_graph: PoseGraphConfig = Field(default_factory=PoseGraphConfig)
    plane_adjustment: PlaneAdjustmentConfig = Field(default_factory=PlaneAdjustmentConfig)
    posterior: PosteriorConfig = Field(default_factory=PosteriorConfig)
    ending: EndingConfig = Field(default_factory=EndingConfig)
    map: MapConfig = Field(default_factory=MapConfig)

    def with_odometry_noise(self, sigma_m: float, sigma_deg: float) -> "SlamConfig":
        """This config with the odometry's stated per-step noise, where the config does not set its own."""
        stated = {"odometry_sigma_m": sigma_m, "odometry_sigma_deg": sigma_deg}
        update = {name: value for name, value in stated.items() if name not in self.motion.model_fields_set}
        return self.model_copy(update={"motion": self.motion.model_copy(update=update)})


def load_slam_config(path: str | Path) -> SlamConfig:
    """The ``slam:`` section of a YAML config file (other sections are left to their stages)."""
    return load_section(path, "slam", SlamConfig, SlamError)
