"""SLAM settings (paper §IV-B). Lengths in metres, angles in degrees at this interface only."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field


class SlamConfig(BaseModel):
    """Every SLAM parameter; a factory builds each stage from these plain values."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    resolution_m: float = Field(0.05, gt=0)  # likelihood and occupancy grid cell
    # point likelihood exp(−d²/2σ²): radio points sit 1–7 cm off their wall (range error ≈ mm,
    # the beam direction quantized to the codebook); σ also absorbs submap blur
    sigma_m: float = Field(0.05, gt=0)
    # specular normals agree to ±σ_ψ (arc peaks locate a wall normal to ~0.1°; the coarse search steps 0.5°)
    normal_sigma_deg: float = Field(1.0, gt=0)
    # points with a normal are scored point-to-plane within this distance of the nearest map point
    plane_reach_m: float = Field(0.5, ge=0)
    project_arcs: bool = False  # arc points placed where their beam meets the arc's wall line (tried: worse)
    min_points: int = Field(8, ge=3)  # a scan with fewer points is skipped with a warning
    submap_scans: int = Field(7, ge=1)  # consecutive scans per submap (MATLAB lidarSLAM's default)
    local_map_scans: int = Field(10, ge=1)  # the front end matches against this many latest scans
    # front end: correlative window around the constant-velocity prediction
    window_m: float = Field(0.30, gt=0)
    window_deg: float = Field(6.0, gt=0)
    angle_step_deg: float = Field(0.5, gt=0)
    # added to every front-end covariance: the response surface treats the points as independent
    # and is over-confident; these are the step errors measured against the truth on paper-cnv
    # (sd 1.5–2.3 cm and 0.3° per scan, seeds 1–5)
    odometry_sigma_m: float = Field(0.02, ge=0)
    odometry_sigma_deg: float = Field(0.3, ge=0)
    # a front-end match whose normalized score is below this is not trusted: the pose is predicted
    min_match_score: float = Field(0.25, ge=0, le=1)
    # loop closure: branch and bound over a wide window
    loop_radius_m: float = Field(3.0, gt=0)  # candidate submaps within this distance
    loop_skip_submaps: int = Field(2, ge=0)  # never the most recent ones
    loop_window_m: float = Field(1.5, gt=0)
    loop_window_deg: float = Field(20.0, gt=0)
    loop_min_score: float = Field(0.35, ge=0, le=1)  # normalized score: mean point likelihood
    loop_gate_chi2: float = Field(16.27, gt=0)  # χ²(3) at 99.9 %: consistency with the graph
    # pose graph
    gnc: bool = True  # loop factors robust to false closures (GncLMOptimizer)
    # a match is degenerate when its surfaces' information (Σ n nᵀ) or its covariance is this
    # elongated (ratio of standard deviations): a direction nothing fixes
    degenerate_ratio: float = Field(4.0, gt=1)
    # along such a direction the step is the median length of this many latest straight steps that
    # observed every direction (the walker's pace), not the last step: one step's speed is a poor
    # guess for many steps ahead
    pace_scans: int = Field(10, ge=1)
