"""report.html: one self-contained page (figures inlined as base64 PNG) with the metrics
table and the run's parameters, written atomically."""

from __future__ import annotations

import base64
import html
import json
from pathlib import Path

import numpy as np

from radioslam.eval.map3d import HORIZONTAL_NZ
from radioslam.io import read_scan, read_tum
from radioslam.io.atomic import atomic_write_text
from radioslam.io.json_io import read_json
from radioslam.io.ply import read_map_points
from radioslam.io.rundir import RunDir
from radioslam.io.slam_summary import read_slam_summary
from radioslam.scene import load_scene
from radioslam.scene.extrude import scene_mesh
from radioslam.slam.status import ScanStatus
from radioslam.viz.fig6 import fig6_figure
from radioslam.viz.map3d import map_3d_figure
from radioslam.viz.status_strip import status_strip


def write_report(out: Path) -> Path:
    run = RunDir(Path(out))
    scene = load_scene(str(run.scene))
    _, truth = read_tum(run.ground_truth)
    _, estimate = read_tum(run.trajectory)
    _, odometry = read_tum(run.trajectory_odometry)
    scans = [read_scan(run.scan_file(k)) for k in range(len(truth))]
    figure = run.root / "fig6.png"
    fig6_figure(figure, scene.segments, truth, odometry, estimate, [s.horizontal() for s in scans], title=scene.name)
    three_d = map_3d_section(run, scene, estimate)
    metrics = read_json(run.metrics)
    summary = read_slam_summary(run.slam_summary)
    strip = run.root / "scan_status.png"
    statuses = [ScanStatus(v) for v in summary.get("scan_status", [])]
    scores = np.array([np.nan if v is None else v for v in summary.get("match_score", [None] * len(statuses))],
                      dtype=float)
    status_strip(strip, statuses, scores)
    strip_image = base64.b64encode(strip.read_bytes()).decode()
    lost = "tracking lost: scans " + ", ".join(str(k) for k in summary.get("lost_scans", [])) \
        if summary.get("tracking_lost") else "tracking held throughout"
    rows = "".join(f"<tr><td>{html.escape(k)}</td><td>{html.escape(_fmt(v))}</td></tr>" for k, v in metrics.items())
    image = base64.b64encode(figure.read_bytes()).decode()
    page = f"""<!doctype html><html><head><meta charset="utf-8"><title>radioslam: {html.escape(scene.name)}</title>
<style>body{{font-family:sans-serif;max-width:1200px;margin:2em auto}}td{{padding:2px 12px}}
pre{{background:#f4f4f4;padding:1em;overflow:auto}}</style></head><body>
<h1>radioslam run: {html.escape(scene.name)}</h1>
<p>{len(truth)} poses. Figure: (a) reflection energy, (b) map without PGO, (c) map with PGO;
true walls in grey, ground truth dashed.</p>
<img alt="Fig. 6" style="width:100%" src="data:image/png;base64,{image}">
{three_d}<h2>Scan statuses</h2><p>{html.escape(lost)}.</p>
<img alt="scan statuses" style="width:100%" src="data:image/png;base64,{strip_image}">
<h2>Metrics</h2><table>{rows}</table>
<h2>Warnings</h2><pre>{html.escape(chr(10).join(summary.get("warnings", [])) or "none")}</pre>
<h2>SLAM parameters</h2><pre>{html.escape(json.dumps(summary.get("config", {}), indent=2))}</pre>
<h2>Scene</h2><pre>{html.escape(run.scene.read_text(encoding="utf-8"))}</pre>
</body></html>
"""
    atomic_write_text(run.report, page)
    return run.report


def map_3d_section(run: RunDir, scene, estimate: np.ndarray) -> str:
    """The 3D map's figure (:mod:`radioslam.viz.map3d`) when map.ply has heights, else nothing."""
    points = read_map_points(run.map_cloud, dims=3) if run.map_cloud.exists() else np.zeros((0, 3))
    if not len(points) or np.ptp(points[:, 2]) == 0:
        return ""
    mesh = scene_mesh(scene)
    surfaces = np.zeros(0)
    if mesh is not None:
        a, b, c = (mesh.vertices[mesh.faces[:, k]] for k in range(3))
        normal = np.cross(b - a, c - a)
        flat = np.abs(normal[:, 2]) > HORIZONTAL_NZ * np.linalg.norm(normal, axis=1)
        surfaces = np.unique(np.round(a[flat, 2], 3))
    height, _ = run.terminal_height_m()
    figure = run.root / "map3d.png"
    map_3d_figure(figure, points, estimate, height, surfaces, title=f"{scene.name}: 3D map from the SLAM poses")
    image = base64.b64encode(figure.read_bytes()).decode()
    return (f'<h2>3D map</h2><p>map.ply: {len(points):,} points from every elevation row, placed by the SLAM '
            f'poses (the SLAM ran on the horizontal row); dashed: the scene\'s true horizontal surfaces.</p>'
            f'<img alt="3D map" style="width:100%" src="data:image/png;base64,{image}">')


def _fmt(value) -> str:
    if isinstance(value, float):
        return f"{value:.4f}"
    if isinstance(value, dict):
        return ", ".join(f"{k} {v:.2f} s" if isinstance(v, float) else f"{k} {v}" for k, v in value.items())
    return str(value)
