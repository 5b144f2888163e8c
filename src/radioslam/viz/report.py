"""report.html (issue #17): one self-contained page a researcher can put in a talk. Its provenance (from
run.json: version, command, seed, scene, channel, each stage), the metrics with names and units, the map
(Fig. 6), the run along its scans (each pose's error for the front end and after PGO, match scores,
statuses), one scan's radar heatmap (Fig. 4(b), the pose the sense stage plotted), the 3D map where there is
one, the warnings, and the configurations folded away. Figures are inlined as base64 PNG; the page is
written atomically."""

from __future__ import annotations

import base64
import html
import json
from pathlib import Path

import numpy as np

from radioslam.eval.map3d import horizontal_surface_heights
from radioslam.eval.metric_table import metric_rows
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
from radioslam.viz.run_timeline import run_timeline

STYLE = """
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;max-width:1200px;margin:1.5em auto;
padding:0 1em;color:#222;line-height:1.45}
h1{margin-bottom:.2em}h2{border-bottom:1px solid #ddd;padding-bottom:.2em;margin-top:1.8em}
img{max-width:100%;height:auto;display:block;margin:.5em 0}
table{border-collapse:collapse;margin:.5em 0}td,th{padding:3px 12px;border-bottom:1px solid #eee;text-align:left;
vertical-align:top}td.num{text-align:right;font-variant-numeric:tabular-nums;white-space:nowrap}
table.provenance td:first-child,table.metrics td:first-child{color:#555}
code,pre{font-family:ui-monospace,Menlo,Consolas,monospace;font-size:.9em}
pre{background:#f6f6f6;padding:.8em;overflow:auto;max-height:32em}
td code{word-break:break-all}
details{margin:.4em 0}summary{cursor:pointer;font-weight:600}
.caption{color:#444;font-size:.95em}.wrap{overflow-x:auto}
"""


def _image(path: Path, alt: str) -> str:
    data = base64.b64encode(path.read_bytes()).decode()
    return f'<img alt="{html.escape(alt)}" src="data:image/png;base64,{data}">'


def _details(summary: str, text: str) -> str:
    return f"<details><summary>{html.escape(summary)}</summary><pre>{html.escape(text)}</pre></details>"


def write_report(out: Path) -> Path:
    run = RunDir(Path(out))
    scene = load_scene(str(run.scene))
    _, truth = read_tum(run.ground_truth)
    _, estimate = read_tum(run.trajectory)
    _, odometry = read_tum(run.trajectory_odometry)
    scans = [read_scan(run.scan_file(k)) for k in range(len(truth))]
    metrics = read_json(run.metrics)
    summary = read_slam_summary(run.slam_summary)
    manifest = read_json(run.root / "run.json") if (run.root / "run.json").exists() else {}
    loops = [(int(lc["anchor"]), int(lc["pose"])) for lc in summary.get("loop_closures", [])]
    fig6 = run.root / "fig6.png"
    fig6_figure(fig6, scene.segments, truth, odometry, estimate, [s.horizontal() for s in scans],
                title=scene.name, loop_closures=loops)
    timeline = run.root / "scan_status.png"
    statuses = [ScanStatus(v) for v in summary.get("scan_status", [])]
    scores = np.array([np.nan if v is None else v for v in summary.get("match_score", [None] * len(statuses))],
                      dtype=float)
    run_timeline(timeline, truth, odometry, estimate, statuses, scores)
    lost = ("tracking was lost at scans " + ", ".join(str(k) for k in summary.get("lost_scans", []))
            if summary.get("tracking_lost") else "tracking held throughout")
    warnings = summary.get("warnings", [])
    page = f"""<!doctype html><html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>radioslam: {html.escape(scene.name)}</title><style>{STYLE}</style></head><body>
<h1>radioslam run: {html.escape(scene.name)}</h1>
{_provenance(manifest, scene, len(truth))}
<h2>Results</h2>
{_metrics_table(metrics)}
<h2>Map (the paper's Fig. 6)</h2>
<p class="caption">(a) each point's reflection energy, placed by the true poses; (b) the map the front end makes
alone; (c) after loop closure and pose graph optimization, the loop closures in purple. True walls in black,
the ground truth dashed, the start as a star. The estimates are aligned onto the ground truth (SE(2)); the map
frame is the terminal's at the first pose.</p>
{_image(fig6, "Fig. 6: reflection energy, map without PGO, map with PGO")}
<h2>Along the run</h2>
<p class="caption">Each pose's position error after the alignment, for the front end and after PGO; the front
end's match score; each scan's status. {html.escape(lost.capitalize())}.</p>
{_image(timeline, "position error per pose, match score and scan status")}
{_heatmap_section(run)}{map_3d_section(run, scene, estimate)}
<h2>Warnings</h2>
{"<ul>" + "".join(f"<li>{html.escape(w)}</li>" for w in warnings) + "</ul>" if warnings else "<p>None.</p>"}
<h2>Configuration</h2>
{_details("Scene and radio (scene.yaml)", run.scene.read_text(encoding="utf-8"))}
{_details("Receiver (the sense stage's settings)", json.dumps(_stage_settings(manifest, "sense"), indent=2))}
{_details("SLAM (slam.json's config)", json.dumps(summary.get("config", {}), indent=2))}
{_details("run.json", json.dumps(manifest, indent=2))}
</body></html>
"""
    atomic_write_text(run.report, page)
    return run.report


def _stage_settings(manifest: dict, stage: str) -> dict:
    return manifest.get("stages", {}).get(stage, {}).get("settings", {})


def _provenance(manifest: dict, scene, poses: int) -> str:
    """Who made the run and how (run.json; a recorder's directory without one says so)."""
    if not manifest:
        return f"<p>{poses} poses. No run.json: the run's provenance is unknown.</p>"
    simulate = _stage_settings(manifest, "simulate")
    versions = manifest.get("versions", {})
    stages = ", ".join(f"{name} {info.get('status', '?')}" for name, info in manifest.get("stages", {}).items()
                       if name != "report")  # this page is the report stage's work
    rows = [("radioslam", versions.get("radioslam", "?")),
            ("command", f"<code>{html.escape(' '.join(map(str, manifest.get('command', []))))}</code>"),
            ("created", html.escape(str(manifest.get("created", "?")))),
            ("run id", f"<code>{html.escape(str(manifest.get('run_id', '?')))}</code>"),
            ("scene", f"{html.escape(str(manifest.get('scene', scene.name)))}, {poses} poses"
                      + (f", SHA-256 <code>{simulate['scene_sha256'][:16]}…</code>" if "scene_sha256" in simulate
                         else "")),
            ("seed", html.escape(str(manifest.get("seed", "?")))),
            ("channel", html.escape(str(simulate.get("channel", "builtin")))),
            ("SNR", f"{scene.radio.snr_db:g} dB per RE (reference echo)"),
            ("stages", html.escape(stages)),
            ("versions", html.escape(", ".join(f"{k} {v}" for k, v in versions.items() if k != "radioslam")))]
    body = "".join(f"<tr><td>{name}</td><td>{value}</td></tr>" for name, value in rows)
    return f'<div class="wrap"><table class="provenance">{body}</table></div>'


def _metrics_table(metrics: dict) -> str:
    def cell(value: str) -> str:  # numbers right-aligned on one line; lists (statuses, seconds) wrap
        kind = "num" if value.replace(".", "", 1).replace("-", "", 1).isdigit() else "text"
        return f'<td class="{kind}">{html.escape(value)}</td>'

    body = "".join(f"<tr><td>{html.escape(name)}</td>{cell(value)}<td>{html.escape(unit)}</td></tr>"
                   for name, value, unit in metric_rows(metrics))
    return (f'<div class="wrap"><table class="metrics"><tr><th>metric</th><th>value</th><th>unit</th></tr>{body}'
            "</table></div>")


def _heatmap_section(run: RunDir) -> str:
    """The sense stage's radar heatmap of one pose (scans/NNNN.png, ``--plot-pose``), if it made one."""
    figures = sorted(run.scans.glob("[0-9][0-9][0-9][0-9]*.png")) if run.scans.is_dir() else []
    if not figures:
        return ""
    pose = int(figures[0].stem)
    return (f"<h2>One scan: pose {pose} (the paper's Fig. 4(b), (c))</h2><p class=\"caption\">(b) every beam's "
            "range profile as a polar heatmap, terminal frame; (c) the radio point cloud the −13 dB rule keeps. "
            "Another pose: <code>--plot-pose N</code> on sense or run.</p>" + _image(figures[0], f"pose {pose}"))


def map_3d_section(run: RunDir, scene, estimate: np.ndarray) -> str:
    """The 3D map's figure (:mod:`radioslam.viz.map3d`) when map.ply has heights, else nothing."""
    points = read_map_points(run.map_cloud, dims=3) if run.map_cloud.exists() else np.zeros((0, 3))
    if not len(points) or np.ptp(points[:, 2]) == 0:
        return ""
    mesh = scene_mesh(scene)
    surfaces = np.zeros(0) if mesh is None else horizontal_surface_heights(mesh)
    height, _ = run.terminal_height_m()
    figure = run.root / "map3d.png"
    map_3d_figure(figure, points, estimate, height, surfaces, title=f"{scene.name}: 3D map from the SLAM poses")
    return ("<h2>3D map</h2><p class=\"caption\">map.ply: "
            f"{len(points):,} points from every elevation row, placed by the SLAM poses (the SLAM ran on the "
            "horizontal row); dashed: the scene's true horizontal surfaces.</p>" + _image(figure, "3D map"))
