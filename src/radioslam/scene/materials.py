"""Wall materials with a directive diffuse-scattering model.

Follows V. Degli-Esposti et al., "Measurement and modelling of scattering from
buildings", IEEE TAP 55(1), 2007 (the "directive model"). A material has
  reflectivity Γ   field reflection coefficient at normal incidence (power Γ²),
  scattering S     fraction S² of the reflected power scattered diffusely,
  directivity α_R  width of the scattering lobe ((1 + cos ψ_R)/2)^α_R about the
                   specular direction,
  transmission T   field transmission coefficient (power T²); T > 0 lets a ray
                   go on to the wall behind (glass, drywall).
For the monostatic terminal the backscatter direction is 2ψ from the specular one
(ψ the incidence angle), so the lobe is cos^{2α}(ψ): strong at normal incidence,
weak at grazing. The lobe is normalized over the circle, F_α = ∫((1+cos x)/2)^α dx.

Values at 28 GHz follow the permittivities of ITU-R P.2040 (Γ = |1−√ε|/(1+√ε)). Each material also names
its ITU-R P.2040 class and a slab thickness: what a ray tracer with ITU materials (Sionna RT, issue #16)
takes in its place; our reflectivity, scattering and directivity then set only the tracer's diffuse part
(its scattering coefficient S and directive lobe α_R, the same Degli-Esposti model).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

import numpy as np


class ItuMaterial(str, Enum):
    """The material classes of ITU-R P.2040-3 Table 3 (1–100 GHz), and the few floor finishes Sionna RT
    adds, by the names Sionna RT uses."""

    VACUUM = "vacuum"
    CONCRETE = "concrete"
    BRICK = "brick"
    PLASTERBOARD = "plasterboard"
    WOOD = "wood"
    GLASS = "glass"
    CLEAR_ACRYLIC = "clear_acrylic"
    CEILING_BOARD = "ceiling_board"
    CHIPBOARD = "chipboard"
    PLYWOOD = "plywood"
    MARBLE = "marble"
    FLOORBOARD = "floorboard"
    VINYL_TILE = "vinyl_tile"
    CARPET_TILE = "carpet_tile"
    ASPHALT_CONCRETE = "asphalt_concrete"
    METAL = "metal"
    VERY_DRY_GROUND = "very_dry_ground"
    MEDIUM_DRY_GROUND = "medium_dry_ground"
    WET_GROUND = "wet_ground"


@dataclass(frozen=True)
class Material:
    reflectivity: float
    scattering: float
    directivity: float
    transmission: float
    itu: ItuMaterial | None = None  # the ITU-R P.2040 class a ray tracer uses instead (None: none given)
    thickness_m: float = 0.1  # the slab's thickness there (its transmission)

    @property
    def lobe_norm(self) -> float:
        """F_α = ∫_{−π}^{π} cos^{2α}(x/2) dx = 2√π Γ(α+½)/Γ(α+1)."""
        a = self.directivity
        return 2.0 * math.sqrt(math.pi) * math.exp(math.lgamma(a + 0.5) - math.lgamma(a + 1.0))

    def backscatter_lobe(self, incidence_rad: np.ndarray) -> np.ndarray:
        """Normalized diffuse backscatter density 2π·cos^{2α}(ψ)/F_α (mean 1 over the circle)."""
        c = np.clip(np.cos(incidence_rad), 0.0, 1.0)
        return (2.0 * np.pi / self.lobe_norm) * c ** (2.0 * self.directivity)


BUILTIN_MATERIALS: dict[str, Material] = {
    "concrete": Material(0.40, 0.40, 4.0, 0.0, ItuMaterial.CONCRETE, 0.2),
    "glass": Material(0.43, 0.20, 10.0, 0.70, ItuMaterial.GLASS, 0.01),
    "metal": Material(0.98, 0.20, 10.0, 0.0, ItuMaterial.METAL, 0.01),
    "wood": Material(0.17, 0.30, 3.0, 0.60, ItuMaterial.WOOD, 0.04),
    "drywall": Material(0.25, 0.30, 3.0, 0.80, ItuMaterial.PLASTERBOARD, 0.0125),
}

# the built-in material of each ITU class that has one: what lends a Mitsuba scene's wall of that class its 2D model
BUILTIN_BY_ITU: dict[ItuMaterial, Material] = {m.itu: m for m in BUILTIN_MATERIALS.values()}
