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

Values at 28 GHz follow the permittivities of ITU-R P.2040 (Γ = |1−√ε|/(1+√ε)).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Material:
    reflectivity: float
    scattering: float
    directivity: float
    transmission: float

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
    "concrete": Material(reflectivity=0.40, scattering=0.40, directivity=4.0, transmission=0.0),
    "glass": Material(reflectivity=0.43, scattering=0.20, directivity=10.0, transmission=0.70),
    "metal": Material(reflectivity=0.98, scattering=0.20, directivity=10.0, transmission=0.0),
    "wood": Material(reflectivity=0.17, scattering=0.30, directivity=3.0, transmission=0.60),
    "drywall": Material(reflectivity=0.25, scattering=0.30, directivity=3.0, transmission=0.80),
}
