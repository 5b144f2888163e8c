"""The scene file schema ★ (DESIGN.md §4, version 1), as pydantic models.

Unknown keys are rejected everywhere; the optional ``radio:`` block is a
:class:`~radioslam.config.RadioConfig`.
"""

from __future__ import annotations

import math
from enum import Enum
from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from radioslam.config import RadioConfig
from radioslam.scene.materials import ItuMaterial

# a scene is a building, not a continent: every length and grid stays bounded (issue #15)
EXTENT_M = 10_000.0
MAX_SEGMENTS = 20_000  # each pose casts a specular ray per segment against every segment
MAX_POSES = 100_000
Coordinate = Annotated[float, Field(ge=-EXTENT_M, le=EXTENT_M)]
Point = tuple[Coordinate, Coordinate]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


class MaterialSpec(_Strict):
    reflectivity: float = Field(ge=0.0, le=1.0)
    scattering: float = Field(ge=0.0, le=1.0)
    directivity: float = Field(ge=0.0, le=100.0)
    transmission: float = Field(0.0, ge=0.0, le=1.0)
    itu: ItuMaterial | None = None  # the ITU-R P.2040 class a ray tracer with ITU materials uses (Sionna RT)
    thickness_m: float = Field(0.1, gt=0.0, le=10.0)  # the slab's thickness there

    @model_validator(mode="after")
    def _energy(self) -> "MaterialSpec":
        if self.reflectivity**2 + self.transmission**2 > 1.0 + 1e-12:
            raise ValueError("reflectivity² + transmission² exceeds 1 (creates energy)")
        return self


class WallSpec(_Strict):
    points: list[Point]
    material: str

    @field_validator("points")
    @classmethod
    def _two_points(cls, v: list[Point]) -> list[Point]:
        if len(v) < 2:
            raise ValueError(f"a polyline needs at least 2 points, got {len(v)}")
        return v


class Heading(str, Enum):
    TANGENT = "tangent"
    FIXED = "fixed"


class CircleSpec(_Strict):
    center: Point
    radius: float = Field(gt=0.0, le=EXTENT_M)
    poses: int = Field(ge=1, le=MAX_POSES)
    heading: Heading = Heading.TANGENT


class TrajectorySpec(_Strict):
    circle: CircleSpec | None = None
    # x, y in metres and the heading θ in radians, counter-clockwise from +x (|θ| ≤ 2π: a degree would pass
    # silently as a wrong heading)
    poses: list[tuple[Coordinate, Coordinate, Annotated[float, Field(ge=-math.tau, le=math.tau)]]] | None = \
        Field(None, max_length=MAX_POSES)

    @field_validator("poses", mode="before")
    @classmethod
    def _radians(cls, v):
        if isinstance(v, list):
            for k, pose in enumerate(v):
                theta = pose[2] if isinstance(pose, (list, tuple)) and len(pose) == 3 else None
                if isinstance(theta, (int, float)) and abs(theta) > math.tau:
                    raise ValueError(f"pose {k}: θ = {theta:g} is not in radians (|θ| ≤ 2π ≈ 6.283); "
                                     f"{theta:g}° is {math.radians(theta):.4f} rad")
        return v

    @model_validator(mode="after")
    def _exactly_one(self) -> "TrajectorySpec":
        if (self.circle is None) == (self.poses is None):
            raise ValueError("give exactly one of 'circle' or 'poses'")
        if self.poses is not None and not self.poses:
            raise ValueError("'poses' is empty")
        return self


class OdometrySpec(_Strict):
    """A drifting wheel/IMU odometry the simulator writes as ``odometry.tum`` (issue #12): each
    step's true motion, scaled by 1 + ``scale_bias``, its heading change plus ``heading_bias_deg``,
    and white noise of ``sigma_m`` (each axis of the step, terminal frame) and ``sigma_deg``. With
    ``gyro_only`` only the headings are written (x and y ``nan``): a gyro's integrated turns."""

    sigma_m: float = Field(0.02, ge=0.0, le=10.0)
    sigma_deg: float = Field(0.5, ge=0.0, le=180.0)
    scale_bias: float = Field(0.0, ge=-0.5, le=0.5)
    heading_bias_deg: float = Field(0.0, ge=-30.0, le=30.0)
    # a gyro (a phone's IMU): only the turns are measured; odometry.tum's x and y are nan (issue #47)
    gyro_only: bool = False


class ExtrudeSpec(_Strict):
    """The 2D walls as vertical walls from the floor (z = 0) to ``height_m``, with an optional floor and
    ceiling (materials; absent: none) spanning the walls' bounding box (issue #16 ★)."""

    height_m: float = Field(gt=0.0, le=1000.0)
    floor: str | None = None
    ceiling: str | None = None


class SceneSpec(_Strict):
    version: Literal[1]
    name: str = Field(min_length=1)
    materials: dict[str, MaterialSpec] = Field(default_factory=dict)
    walls: list[WallSpec] | None = Field(None, min_length=1)
    mitsuba: str | None = Field(None, min_length=1)  # a Mitsuba XML scene (Sionna's), instead of walls (issue #16 ★)
    trajectory: TrajectorySpec
    radio: RadioConfig = Field(default_factory=RadioConfig)
    odometry: OdometrySpec | None = None  # optional: the simulator also writes a drifting odometry
    extrude: ExtrudeSpec | None = None  # optional: the walls in 3D (a height, a floor, a ceiling)

    @model_validator(mode="after")
    def _segment_count(self) -> "SceneSpec":
        if (self.walls is None) == (self.mitsuba is None):
            raise ValueError("give exactly one of 'walls' or 'mitsuba'")
        if self.mitsuba is not None and self.extrude is not None:
            raise ValueError("a mitsuba scene is 3D already: 'extrude' is for walls")
        segments = sum(len(w.points) - 1 for w in self.walls or [])
        if segments > MAX_SEGMENTS:
            raise ValueError(f"{segments:,} wall segments: at most {MAX_SEGMENTS:,}")
        return self
