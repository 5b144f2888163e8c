"""Table I under hardware impairments (issue #13, point 5): each impairment alone, then all of them
as the paper's prototype might have them (``prototype``), ranging RMSE of the refined peak (T2: the
receiver's bracketed refinement, and the paper's bisection on the same captures) against the plain
N_c-point IFFT peak (T1's grid).

The profile is an estimate from the prototype's parts (paper §V, Table II), not a measurement; each
value and why is in docs/architecture.md (§ Hardware impairments).
"""

from __future__ import annotations

from dataclasses import dataclass

from radioslam.config import Impairments, RadioConfig
from radioslam.eval.experiments.table1 import Table1Result, run_table1
from radioslam.progress import SILENT, Progress

# iq: a mixer's 30–35 dB image rejection; adc: the USRP-2974's 14 bits; pa: driven for range; elements:
# uncalibrated phase shifters; drift: temperature between calibration and use; phase-noise, leakage and
# extended: below (docs/architecture.md)
PROFILES: dict[str, Impairments] = {
    "ideal": Impairments(),
    "iq": Impairments(iq_gain_db=0.3, iq_phase_deg=2.0),
    "adc": Impairments(adc_bits=14, adc_backoff_db=12.0),
    "pa": Impairments(pa_backoff_db=6.0, pa_smoothness=2.0),
    "elements": Impairments(element_gain_db=1.0, element_phase_deg=10.0, element_seed=1),
    "drift": Impairments(hardware_delay_drift_s=100e-12),
    # a 28 GHz PLL with −90 dBc/Hz at 100 kHz: a Wiener linewidth of π·f²·L(f) ≈ 31 Hz, one LO for TX and RX
    "phase-noise": Impairments(phase_noise_linewidth_hz=31.0),
    # the leakage's gain and phase since its calibration (temperature): cancelled at its calibrated lag
    "leakage": Impairments(leakage_drift_db=0.5, leakage_drift_deg=5.0),
    # the 1 m plate as physical-optics facets: an extended target, not a point
    "extended": Impairments(specular_facets=True),
}
PROFILES["prototype"] = Impairments(**{k: v for p in PROFILES.values() for k, v in p.model_dump(exclude_defaults=True)
                                       .items()})


@dataclass(frozen=True)
class ImpairmentRow:
    profile: str
    rmse_ifft_m: float
    rmse_refined_m: float  # the receiver's refinement (bracketed)
    rmse_paper_bisection_m: float  # the paper's bisection, the same captures
    hardware_delay_error_s: float

    def to_json(self) -> dict:
        return {"profile": self.profile, "rmse_ifft_m": self.rmse_ifft_m, "rmse_refined_m": self.rmse_refined_m,
                "rmse_paper_bisection_m": self.rmse_paper_bisection_m,
                "hardware_delay_error_s": self.hardware_delay_error_s}


def table1_under(profile: str, trials: int = 20, seed: int = 0, crb: bool = True,
                 progress: Progress = SILENT) -> Table1Result:
    """Table I with the radio's impairments set to ``PROFILES[profile]`` (CRB sweep optional)."""
    radio = RadioConfig(impairments=PROFILES[profile])
    return run_table1(radio, trials, seed, **({} if crb else {"crb_snr_db": ()}), progress=progress)


def run_impairment_table(trials: int = 20, seed: int = 0, progress: Progress = SILENT) -> list[ImpairmentRow]:
    """Table I's ranging RMSE under every profile, one row each (the same seeds throughout)."""
    rows = []
    for name in PROFILES:
        r = table1_under(name, trials, seed, crb=False, progress=progress)
        rows.append(ImpairmentRow(name, r.rmse_ifft_m, r.rmse_bisection_m, r.rmse_paper_bisection_m,
                                  r.hardware_delay_est_s - r.hardware_delay_true_s))
    return rows
