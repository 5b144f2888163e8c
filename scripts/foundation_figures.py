"""Measure every figure issue #2 names and print them against their targets.

    python scripts/foundation_figures.py

The same properties are asserted by the test suite; this prints the numbers.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import sigmf
from py3gpp import nrPSS
from scipy.signal import find_peaks

from radioslam.antenna import BeamSet, beam_angle
from radioslam.config import SPEED_OF_LIGHT, RadioConfig
from radioslam.io import read_capture, write_capture
from radioslam.nr import demodulate, pss
from radioslam.scene import builtin_scene, cast_rays, scene_from_mapping
from radioslam.sim import Simulator, echo_paths, measured_snr_db, strongest_echo
from radioslam.sim.noise import reference_scene

ROWS: list[tuple[str, str, str, bool]] = []


def report(name: str, value: str, target: str, ok: bool) -> None:
    ROWS.append((name, value, target, ok))


def pss_figures() -> None:
    same = all(np.array_equal(pss(k), nrPSS(k)) for k in range(3))
    report("pss(k) == py3gpp nrPSS(k), k = 0,1,2", str(same), "True", same)
    corr = np.array([[np.dot(pss(k), np.roll(pss(k), s)) for s in range(127)] for k in range(3)])
    off = corr[:, 1:]
    ok = np.all(corr[:, 0] == 127) and np.all(off == -1)
    report("PSS periodic autocorrelation", f"zero lag {corr[0, 0]:.0f}, others {off.min():.0f}…{off.max():.0f}",
           "127 and −1", bool(ok))


def _sidelobe_db(gain: np.ndarray) -> float:
    peaks, _ = find_peaks(gain)
    levels = np.sort(gain[peaks])[::-1]
    return float(10 * np.log10(levels[1] / levels[0]))


def beam_figures() -> None:
    edges = np.degrees(beam_angle(np.array([-23, 23]), 6))
    report("beam angles at the edges (deg)", f"{edges[0]:.2f}, {edges[1]:.2f}", "±45.95",
           bool(np.allclose(np.abs(edges), 45.95, atol=0.005)))
    beams = BeamSet(8, 6, 23, 4, element_exponent=0.0)
    theta = np.linspace(-np.pi / 2 + 1e-6, np.pi / 2 - 1e-6, 400_001)
    two_way = beams.two_way_gain(theta)[23]  # ϖ of the boresight beam = one-way power × N
    one = _sidelobe_db(two_way)
    two = _sidelobe_db(two_way**2)
    report("one-way array factor first sidelobe (dB)", f"{one:.2f}", "−12.8", abs(one + 12.8) < 0.05)
    report("two-way first sidelobe (dB)", f"{two:.2f}", "−25.6", abs(two + 25.6) < 0.1)


def raycast_figures() -> None:
    half = 4.0
    room = scene_from_mapping({"version": 1, "name": "room", "walls": [{"points": [[-half, -half], [half, -half],
                              [half, half], [-half, half], [-half, -half]], "material": "concrete"}],
                              "trajectory": {"poses": [[0, 0, 0]]}})
    trans = room.material_array("transmission")
    normals = cast_rays(np.zeros(2), np.arange(4) * np.pi / 2, room.segments, trans, 1, 100)
    err_normals = np.max(np.abs(normals.distance[:, 0] - half))
    rng = np.random.default_rng(0)
    origins = rng.uniform(-3.5, 3.5, (500, 2))
    angles = rng.uniform(-np.pi, np.pi, (500, 20))
    worst = 0.0
    for o, a in zip(origins, angles):  # 500 origins × 20 rays, each cast vectorized
        d = cast_rays(o, a, room.segments, trans, 1, 100).distance[:, 0]
        c, s = np.cos(a), np.sin(a)
        with np.errstate(divide="ignore"):
            tx = np.where(c > 0, (half - o[0]) / c, (-half - o[0]) / c)
            ty = np.where(s > 0, (half - o[1]) / s, (-half - o[1]) / s)
        worst = max(worst, float(np.max(np.abs(d - np.minimum(tx, ty)))))
    report("ray caster: room centre along the 4 normals, max |error| (m)", f"{err_normals:.1e}", "≤ 1e-9",
           err_normals <= 1e-9)
    report("ray caster: 10 000 random rays, max |error| (m)", f"{worst:.1e}", "≤ 1e-9", worst <= 1e-9)


def delay_figures() -> None:
    worst_bistatic, worst_2r = 0.0, 0.0
    for r in np.arange(1, 17) * 0.8:
        scene = builtin_scene(f"single-plate:{r:.1f}")
        radio = scene.radio
        paths = echo_paths(scene, scene.poses[0])
        beams = BeamSet.from_config(radio)
        b = np.flatnonzero((beams.orientation == 0) & (beams.index == 0))[0]
        total = paths.delay_s[strongest_echo(beams, paths, b)] + radio.hardware_delay_s
        exact = 2 * np.sqrt(r**2 + radio.array_baseline_m**2 / 4) / SPEED_OF_LIGHT + radio.hardware_delay_s
        worst_bistatic = max(worst_bistatic, abs(total - exact))
        worst_2r = max(worst_2r, abs(total - (2 * r / SPEED_OF_LIGHT + radio.hardware_delay_s)))
    report("single-plate 0.8…12.8 m: strongest path − (2R/c + T_H), max (s)",
           f"{worst_2r:.2e} (= {worst_2r * SPEED_OF_LIGHT / 2 * 1e3:.2f} mm, the 5 cm TX/RX offset)",
           "≈ 0", worst_2r * SPEED_OF_LIGHT / 2 < 1e-3)
    report("… against the bistatic 2√(R²+b²/4)/c + T_H, max (s)", f"{worst_bistatic:.1e}", "≤ 1e-15",
           worst_bistatic <= 1e-15)


def snr_figures() -> None:
    for snr in (0.0, 10.0, 20.0):
        radio = RadioConfig(snr_db=snr, isolation_db=400.0)
        sim = Simulator.from_scene(reference_scene(radio))
        values = []
        for seed in range(5):
            cap = sim.simulate_pose(0, np.random.default_rng(seed))
            b = int(np.flatnonzero((cap.orientation == 0) & (cap.beam_index == 0))[0])
            timing = int(np.floor(radio.hardware_delay_s * radio.sample_rate_hz))
            y = demodulate(cap.samples[b].astype(complex), cap.useful_starts()[b, 1:] + timing, sim.numerology)
            values.append(measured_snr_db(y, cap.tx_symbols()[b]))
        dev = np.max(np.abs(np.array(values) - snr))
        report(f"measured per-RE SNR of the reference echo at {snr:.0f} dB (5 seeds)",
               f"mean {np.mean(values):.2f} dB, max |dev| {dev:.2f} dB", "within 0.3 dB", dev <= 0.3)


def sigmf_figures() -> None:
    cap = Simulator.from_scene(builtin_scene("paper-cnv")).simulate_pose(0, np.random.default_rng(1))
    with tempfile.TemporaryDirectory() as tmp:
        meta = write_capture(cap, Path(tmp) / "0000")
        back = read_capture(meta)
        exact = all(np.array_equal(getattr(back, f), getattr(cap, f)) for f in
                    ("samples", "tx_bits", "orientation", "beam_index", "beam_angle_rad", "symbol_indices"))
        sigmf.fromfile(str(meta)).validate()
        size = (Path(tmp) / "0000.sigmf-data").stat().st_size
    report("SigMF round trip bit-exact", str(exact), "True", exact)
    report("SigMF metadata passes sigmf validation", "True", "True", True)
    report("SigMF recording per pose (MB)", f"{size / 1e6:.1f}", "-", True)


def cli_figures() -> None:
    base = ("version: 1\nname: t\nwalls:\n  - {points: [[-5, -5], [5, -5], [5, 5], [-5, 5], [-5, -5]], "
            "material: concrete}\ntrajectory:\n  poses: [[0, 0, 0]]\n")
    cases = {
        "unknown key": base + "colour: red\n",
        "missing walls": base.split("walls:")[0] + "trajectory:\n  poses: [[0, 0, 0]]\n",
        "one-point polyline": base.replace("[[-5, -5], [5, -5], [5, 5], [-5, 5], [-5, -5]]", "[[1, 1]]"),
        "unknown material": base.replace("concrete", "cheese"),
        "pose within 0.2 m": base.replace("[[0, 0, 0]]", "[[4.85, 0, 0]]"),
        "non-YAML": "walls: [ {\n",
    }
    with tempfile.TemporaryDirectory() as tmp:
        for label, text in cases.items():
            path = Path(tmp) / "scene.yaml"
            path.write_text(text)
            out = subprocess.run([sys.executable, "-m", "radioslam.cli", "simulate", str(path), "--out",
                                  str(Path(tmp) / "o")], capture_output=True, text=True)
            line = out.stderr.strip()
            ok = out.returncode == 2 and len(line.splitlines()) == 1 and "Traceback" not in line
            report(f"bad scene: {label}", f"exit {out.returncode}: {line.replace(tmp, '…')}", "exit 2, one line", ok)


def main() -> None:
    for step in (pss_figures, beam_figures, raycast_figures, delay_figures, snr_figures, sigmf_figures,
                 cli_figures):
        step()
    width = max(len(r[0]) for r in ROWS)
    for name, value, target, ok in ROWS:
        print(f"{'ok ' if ok else 'BAD'} {name:<{width}}  {value}   [target {target}]")
    if "--json" in sys.argv:
        print(json.dumps([dict(zip(("figure", "value", "target", "ok"), r)) for r in ROWS]))
    sys.exit(0 if all(r[3] for r in ROWS) else 1)


if __name__ == "__main__":
    main()
