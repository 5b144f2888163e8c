"""Table I: ranging error of a 1 m² metal plate on the array normal, 0.8 … 12.8 m (paper §V-A),
after eq. (11) calibration; and the bisection's RMSE against the Cramér–Rao bound over SNR.

ε1 is the N_c-point IFFT peak alone (a 1.22 m grid), ε2 the refined peak (T2) as the receiver
refines it (bracketed by default; the ``bisection`` names of the paper's ε2 are kept), and ε2 of the
paper's fractional-IFFT bisection on the same captures (``paper_bisection``).
Every trial is a fresh waveform-mode capture (new noise and data) sensed from IQ.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from radioslam.config import RadioConfig
from radioslam.eval.crb import range_crb_m
from radioslam.eval.point_targets import capture_point_targets, nearest_beam, point_paths
from radioslam.progress import SILENT, Progress
from radioslam.sensing import Receiver, Refinement, SensingConfig, estimate_hardware_delay
from radioslam.sensing.detect import leakage_cancelled
from radioslam.sim.calibration_targets import calibration_ranges, plate_simulator, simulate_calibration

NEAR_GATE_M = 0.3  # Table I starts at 0.8 m; its ε1 (the IFFT grid peak) is searched from here too


@dataclass(frozen=True)
class Table1Result:
    ranges_m: np.ndarray
    err_ifft_m: np.ndarray  # mean signed error per range
    err_bisection_m: np.ndarray  # the receiver's refinement
    rmse_ifft_m: float
    rmse_bisection_m: float
    hardware_delay_est_s: float
    hardware_delay_true_s: float
    trials: int
    crb_snr_db: np.ndarray
    crb_rmse_m: np.ndarray
    crb_m: np.ndarray
    err_paper_bisection_m: np.ndarray  # the paper's bisection, the same captures
    rmse_paper_bisection_m: float

    @property
    def crb_ratio(self) -> float:
        return float(np.max(self.crb_rmse_m / self.crb_m))

    def to_json(self) -> dict:
        return {"ranges_m": self.ranges_m.tolist(), "err_ifft_m": self.err_ifft_m.tolist(),
                "err_bisection_m": self.err_bisection_m.tolist(), "rmse_ifft_m": self.rmse_ifft_m,
                "rmse_bisection_m": self.rmse_bisection_m, "hardware_delay_est_s": self.hardware_delay_est_s,
                "hardware_delay_true_s": self.hardware_delay_true_s, "trials": self.trials,
                "crb_ratio": self.crb_ratio, "crb_snr_db": self.crb_snr_db.tolist(),
                "crb_rmse_m": self.crb_rmse_m.tolist(), "crb_m": self.crb_m.tolist(),
                "err_paper_bisection_m": self.err_paper_bisection_m.tolist(),
                "rmse_paper_bisection_m": self.rmse_paper_bisection_m}


def plate_errors(radio: RadioConfig, receiver: Receiver, paper: Receiver, range_m: float, trials: int, seed: int,
                 progress: Progress = SILENT):
    """(ε1, ε2, ε2 of ``paper``, the same receiver refining by the paper's bisection) of ``trials``
    captures of the plate at ``range_m``, each (trials,)."""
    sim = plate_simulator(radio, range_m)
    e1, e2, e3 = [], [], []
    for child in np.random.SeedSequence(seed).spawn(trials):
        capture = sim.simulate_pose(0, np.random.default_rng(child))
        res = receiver.sense(capture)
        # the N_c-point IFFT peak alone, on the profile the receiver searches (the leakage cancelled)
        searched = leakage_cancelled(res.spectrum, receiver.range_gate(capture, res.window_offset))
        power = np.abs(searched.profile()[0]) ** 2
        gated = np.where(res.profile_range_m[0] >= NEAR_GATE_M, power, -np.inf)
        e1.append(res.profile_range_m[0, np.argmax(gated)] - range_m)
        e2.append(res.range_m[0, 0] - range_m)
        e3.append(paper.sense(capture).range_m[0, 0] - range_m)
        progress.advance()
    return np.array(e1), np.array(e2), np.array(e3)


def crb_sweep(radio: RadioConfig, snr_db: np.ndarray, trials: int, seed: int,
              progress: Progress = SILENT) -> tuple[np.ndarray, np.ndarray]:
    """RMSE of the bisection for a point target at a random range in 4.5–5.5 m, and the CRB."""
    receiver = Receiver(radio, radio.hardware_delay_s, SensingConfig(min_range_m=NEAR_GATE_M))
    row = nearest_beam(radio, 0.0)
    rng = np.random.default_rng(seed)
    rmse = []
    for snr in snr_db:
        err = []
        for _ in range(trials):
            truth = rng.uniform(4.5, 5.5)
            cap = capture_point_targets(radio, point_paths(radio, truth, 0.0, snr), [row], rng)
            err.append(receiver.sense(cap).range_m[0, 0] - truth)
            progress.advance()
        rmse.append(float(np.sqrt(np.mean(np.square(err)))))
    crb = range_crb_m(radio.n_subcarriers, radio.subcarrier_spacing_hz, radio.symbols_per_beam, snr_db)
    return np.array(rmse), np.asarray(crb)


def run_table1(radio: RadioConfig | None = None, trials: int = 20, seed: int = 0,
               crb_snr_db=(0.0, 5.0, 10.0, 15.0, 20.0), crb_trials: int = 100,
               progress: Progress = SILENT) -> Table1Result:
    radio = radio or RadioConfig()
    ranges = calibration_ranges(radio)  # the paper's Table I ranges are its calibration ranges
    # 1. eq. (11) calibration on its own plate measurements (other noise and data than the trials), and
    #    the leakage from an empty sweep
    plates, empty = simulate_calibration(radio, ranges, seed + 1)
    cal = estimate_hardware_delay(plates, ranges, empty=empty)
    receiver = Receiver(radio, cal.hardware_delay_s, SensingConfig(min_range_m=NEAR_GATE_M), cal.leakage)
    paper = Receiver(radio, cal.hardware_delay_s,
                     SensingConfig(min_range_m=NEAR_GATE_M, refine=Refinement.PAPER_BISECTION), cal.leakage)
    # 2. ε1 and ε2 (the receiver's refinement and the paper's bisection) over many noise trials per range
    progress.start("Table I: plates", len(ranges) * trials)
    errors = [plate_errors(radio, receiver, paper, float(r), trials, seed + 100 + k, progress)
              for k, r in enumerate(ranges)]
    e1, e2, e3 = (np.array([e[i] for e in errors]) for i in range(3))
    # 3. the bisection against the CRB (calibration exact here, to isolate the estimator)
    snr = np.asarray(crb_snr_db, dtype=np.float64)
    progress.start("Table I: CRB sweep", len(snr) * crb_trials)
    rmse, crb = crb_sweep(radio, snr, crb_trials, seed + 2, progress)
    return Table1Result(ranges, e1.mean(axis=1), e2.mean(axis=1), float(np.sqrt(np.mean(e1**2))),
                        float(np.sqrt(np.mean(e2**2))), cal.hardware_delay_s, radio.hardware_delay_s, trials,
                        snr, rmse, crb, e3.mean(axis=1), float(np.sqrt(np.mean(e3**2))))
