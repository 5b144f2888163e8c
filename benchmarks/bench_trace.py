"""Benchmark: the per-pose trace of each channel backend, and Sionna's trace cache (issue #16, point 4).

On paper-cnv extruded to 3 m walls (diffuse scattering on, Sionna's default 2·10⁵ diffuse samples per
source unless ``--samples``), per pose:
- the built-in caster's ``paths`` (2D, and the 2.5D fan with a floor and ceiling and 7 elevation rows);
- Sionna RT's ``paths`` on a miss (traced, then stored in the cache) and on a hit (read back and
  beamformed), with the archive's size.
The first Sionna call also compiles Dr.Jit's kernels: it is timed apart (``first_s``). Not a test: run
it on an idle machine and quote the medians of one run.

    python benchmarks/bench_trace.py [--poses 6] [--samples 200000]
"""

from __future__ import annotations

import argparse
import platform
import tempfile
import time

import numpy as np

from radioslam.io.trace_cache import TraceCache
from radioslam.scene import load_scene
from radioslam.scene.loader import scene_from_mapping
from radioslam.sim.channel_backend import BuiltinChannel

TARGET_S = 5.0  # issue #16: a Sionna trace of the extruded paper-cnv, per pose


def extruded_paper_cnv(samples: int, rows: int = 1, surfaces: bool = False):
    spec = load_scene("paper-cnv").spec.model_dump(mode="json", exclude_none=True)
    spec["extrude"] = {"height_m": 3.0, **({"floor": "concrete", "ceiling": "concrete"} if surfaces else {})}
    spec["radio"] = {**spec.get("radio", {}), "sionna_samples": samples, "elevation_beams": rows}
    return scene_from_mapping(spec)


def timed(call, poses) -> tuple[np.ndarray, object]:
    times, out = [], None
    for pose in poses:
        start = time.perf_counter()
        out = call(pose)
        times.append(time.perf_counter() - start)
    return np.array(times), out


def row(name: str, times: np.ndarray, extra: str = "") -> str:
    return f"| {name} | {np.median(times):.3f} | {times.min():.3f} | {times.max():.3f} | {extra} |"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--poses", type=int, default=6)
    parser.add_argument("--samples", type=int, default=200_000)
    args = parser.parse_args()
    scene = extruded_paper_cnv(args.samples)
    poses = scene.poses[np.linspace(0, len(scene.poses) - 1, args.poses).astype(int)]
    lines = ["| channel | median s/pose | min | max | |", "|---|---|---|---|---|"]
    caster, _ = timed(BuiltinChannel(scene, scene.radio).paths, poses)
    lines.append(row("builtin caster, flat", caster))
    fan_scene = extruded_paper_cnv(args.samples, rows=7, surfaces=True)
    fan, _ = timed(BuiltinChannel(fan_scene, fan_scene.radio).paths, poses)
    lines.append(row("builtin 2.5D fan, 7 rows, floor + ceiling", fan))
    from radioslam.sim.sionna_channel import SionnaChannel  # the optional extra

    with tempfile.TemporaryDirectory() as folder:
        cache = TraceCache(folder)
        channel = SionnaChannel(scene, scene.radio, cache=cache)
        start = time.perf_counter()
        channel.paths(scene.poses[1])  # Dr.Jit compiles its kernels on the first trace
        first = time.perf_counter() - start
        miss, paths = timed(channel.paths, poses)
        hit, _ = timed(channel.paths, poses)
        sizes = [f.stat().st_size / 2**20 for f in cache.directory.glob("*.npz")]
    lines.append(row(f"sionna, traced ({args.samples:,} samples)", miss,
                     f"{len(paths):,} paths; first call {first:.1f} s; target ≤ {TARGET_S:g} s"))
    lines.append(row("sionna, from the cache", hit, f"{np.median(sizes):.1f} MiB per pose; {cache.hits} hits"))
    print(f"per-pose paths of paper-cnv extruded (3 m walls, diffuse on), {args.poses} poses, "
          f"{platform.processor() or platform.machine()}")
    print("\n".join(lines))
    print(f"cache hit / trace: {np.median(hit) / np.median(miss):.3f}")


if __name__ == "__main__":
    main()
