"""The two channel backends on matched geometry (issue #16, point 2): the built-in 2D caster against
Sionna RT on the same scene extruded to 3D, for a single metal plate and for paper-cnv (walls 3 m high,
no floor or ceiling), and, to show what Sionna adds, paper-cnv with a concrete floor and ceiling and
glass-door (a glass wall Sionna refracts through, where the caster passes a fixed transmission T).

Per pose and beam it compares:
- the strongest path's delay, as path length (on the beams whose strongest path is specular in both:
  the diffuse ones are sampled differently, rays of a fan against Sionna's random diffuse samples);
- the beam's power (every path on it), split by which kind of path dominates it;
- the point clouds the receiver makes of each backend's waveform IQ (same seed, no leakage, the hardware
  delay known): per point of one cloud, the distance to the nearest point of the other on the same beam.

Needs Sionna RT (``pip install 'radioslam[sionna]'`` and an LLVM; see docs/architecture.md).

    python benchmarks/cross_check_sionna.py [--poses 0 15 30 45] [--seed 1] [--elevation-beams 7]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from radioslam.antenna.codebook import BeamSet
from radioslam.choices import ChannelKind
from radioslam.eval.map3d import match_surfaces
from radioslam.scene import load_scene
from radioslam.scene.extrude import scene_mesh
from radioslam.scene.loader import scene_from_mapping
from radioslam.sensing import Receiver
from radioslam.sim import Simulator, beam_path_gains
from radioslam.sim.paths import PathKind
from radioslam.slam.se2 import transform_points

C = 299_792_458.0


def plate_scene(elevation_beams: int = 1):
    plate = [{"points": [[3, -1], [3, 1]], "material": "metal"}]
    return scene_from_mapping({"version": 1, "name": "plate", "walls": plate,
                               "trajectory": {"poses": [[0, 0, 0.0], [0, 0, 0.3], [0.5, 0.4, -0.5], [-1, 0, 2.0]]},
                               "extrude": {"height_m": 3.0},
                               "radio": {"isolation_db": 400, "elevation_beams": elevation_beams}})


def extruded(name: str, floor: str | None = None, ceiling: str | None = None, elevation_beams: int = 1):
    spec = load_scene(name).spec.model_dump(mode="json", exclude_none=True)
    surfaces = {key: value for key, value in (("floor", floor), ("ceiling", ceiling)) if value}
    spec["extrude"] = {"height_m": 3.0, **surfaces}
    spec["radio"] = {**spec.get("radio", {}), "isolation_db": 400, "elevation_beams": elevation_beams}
    return scene_from_mapping(spec)


def compare_paths(beams, builtin, sionna):
    """Per beam: where the strongest path is specular in both, its delay difference (m of path) and its
    gain difference on the beam (dB); where a diffuse path dominates in both, the beam's power difference
    (dB, every path); and the number of beams whose strongest path is specular in Sionna only."""
    gb, gs = beam_path_gains(beams, builtin), beam_path_gains(beams, sionna)
    sb, ss = np.argmax(np.abs(gb), axis=1), np.argmax(np.abs(gs), axis=1)
    specular = (builtin.kind[sb] == PathKind.SPECULAR) & (sionna.kind[ss] == PathKind.SPECULAR)
    diffuse = (builtin.kind[sb] == PathKind.DIFFUSE) & (sionna.kind[ss] == PathKind.DIFFUSE)
    delay = np.abs(builtin.delay_s[sb] - sionna.delay_s[ss]) * C
    rows = np.arange(len(beams))
    strongest = 20 * np.log10(np.abs(gs[rows, ss]) / np.abs(gb[rows, sb]))
    power = 10 * np.log10((np.abs(gs) ** 2).sum(axis=1) / (np.abs(gb) ** 2).sum(axis=1))
    sionna_only = int(np.sum((sionna.kind[ss] == PathKind.SPECULAR) & ~specular))
    return delay[specular], strongest[specular], power[diffuse], sionna_only


def nearest_same_beam(a, b) -> np.ndarray:
    """Per point of scan a, the distance (in 3D) to the nearest point of scan b seen on the same beam (the
    same orientation, azimuth and elevation row; inf: none)."""
    out = np.full(len(a), np.inf)
    key_a, key_b = ((s.orientation * 100 + s.elevation_beam + 50) * 1000 + s.beam for s in (a, b))
    xa, xb = a.xyz, b.xyz
    for key in np.intersect1d(key_a, key_b):
        ia, ib = np.flatnonzero(key_a == key), np.flatnonzero(key_b == key)
        out[ia] = np.min(np.linalg.norm(xa[ia, None] - xb[None, ib], axis=2), axis=1)
    return out


def cross_check(label, scene, poses, seed):
    beams = BeamSet.from_config(scene.radio)
    sims = {kind: Simulator.from_scene(scene, channel=kind) for kind in ChannelKind}
    receiver = Receiver(scene.radio, scene.radio.hardware_delay_s)
    delays, spec_power, diff_power, extra, dist_sb, dist_bs, counts, seconds = [], [], [], 0, [], [], [], []
    horizontal_sb, off_mesh = [], {kind: [] for kind in ChannelKind}
    mesh = scene_mesh(scene)
    for i in poses:
        tick = time.perf_counter()
        sionna = sims[ChannelKind.SIONNA].channel.paths(scene.poses[i], leakage=False)
        seconds.append(time.perf_counter() - tick)
        builtin = sims[ChannelKind.BUILTIN].channel.paths(scene.poses[i], leakage=False)
        d, sp, dp, more = compare_paths(beams, builtin, sionna)
        delays.append(d), spec_power.append(sp), diff_power.append(dp)
        extra += more
        scans = {kind: receiver.sense(sim.capture_from_paths(sim.channel.paths(scene.poses[i]),
                                                              np.random.default_rng([seed, i]), i)).scan
                 for kind, sim in sims.items()}
        b, s = scans[ChannelKind.BUILTIN], scans[ChannelKind.SIONNA]
        dist_sb.append(nearest_same_beam(s, b)), dist_bs.append(nearest_same_beam(b, s))
        horizontal_sb.append(s.elevation_beam == 0)
        counts.append((len(b), len(s)))
        for kind, scan in scans.items():  # each point's distance to the true surfaces
            world = np.column_stack([transform_points(scene.poses[i], scan.xy), scan.z + scene.radio.height_m])
            off_mesh[kind].append(match_surfaces(world, mesh).distance_m)
    d, sp, dp = (np.concatenate(x) for x in (delays, spec_power, diff_power))
    sb, bs = np.concatenate(dist_sb), np.concatenate(dist_bs)
    n_b, n_s = np.sum(counts, axis=0)
    within = lambda x: f"{np.mean(x <= 0.05):.0%}"  # noqa: E731
    print(f"| {label} | {len(poses)} | {np.median(seconds):.1f} s | "
          f"{len(d)}: {np.mean(d <= 1e-3):.0%} within 1 mm, median {np.median(d) * 1e3:.4f} mm | "
          f"{np.median(sp):+.2f} ({sp.min():+.2f} … {sp.max():+.2f}) | "
          f"{len(dp)}: {np.median(dp) if len(dp) else np.nan:+.1f} | "
          f"{n_b} / {n_s} | {within(sb)} ({np.median(sb[np.isfinite(sb)]) * 100:.1f} cm) | "
          f"{within(bs)} | {extra} |")
    if scene.radio.elevation_beams > 1:
        level = np.concatenate(horizontal_sb)
        on_surface = {kind.value: f"{within(np.concatenate(x))} (median {np.median(np.concatenate(x)) * 100:.1f} cm)"
                      for kind, x in off_mesh.items()}
        print(f"|  ↳ 3D | Sionna points within 5 cm of a builtin one: horizontal row {within(sb[level])}, other rows "
              f"{within(sb[~level])} ({(~level).sum()} points) | points within 5 cm of the true surfaces: builtin "
              f"{on_surface['builtin']}, Sionna {on_surface['sionna']} |||||||")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--poses", type=int, nargs="+", default=[0, 15, 30, 45])
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--elevation-beams", type=int, default=1,
                        help="rows of the elevation codebook (3D points; the closed rooms are then left out: "
                             "beams × Sionna's paths outgrow this machine)")
    args = parser.parse_args()
    rows = args.elevation_beams
    print("| scene | poses | Sionna s/pose | specular beams: strongest-path delay diff | its gain diff dB, "
          "median (range) | diffuse beams: power diff dB, median | points builtin / Sionna | Sionna points within 5 cm "
          "of a builtin one (median) | builtin points within 5 cm of a Sionna one | beams specular in Sionna only |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    cross_check("single plate (metal, 2 m × 3 m at 3 m)", plate_scene(rows), range(4), args.seed)
    cross_check("paper-cnv extruded, no floor or ceiling", extruded("paper-cnv", elevation_beams=rows), args.poses,
                args.seed)
    if rows > 1:
        return
    cross_check("paper-cnv extruded, concrete floor and ceiling", extruded("paper-cnv", "concrete", "concrete"),
                args.poses, args.seed)
    glass = extruded("glass-door")
    cross_check("glass-door extruded (glass: Sionna refracts through a 1 cm slab)", glass,
                sorted(set(np.linspace(0, len(glass.poses) - 1, 4).astype(int).tolist())), args.seed)


if __name__ == "__main__":
    main()
