"""metrics.json as a table a person reads (issue #17): each metric's name, its value in a unit that suits
its size, at a precision the measurement carries. The keys stay metrics.json's ★ ones (DESIGN.md §6)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Metric:
    label: str
    unit: str = ""
    scale: float = 1.0  # metrics.json's SI value × scale = the value shown in ``unit``
    digits: int = 2


METRICS: dict[str, Metric] = {
    "ate_rmse_m": Metric("ATE RMSE, SLAM", "cm", 100.0, 2),
    "ate_rmse_odometry_m": Metric("ATE RMSE, front end (odometry)", "cm", 100.0, 2),
    "rpe_rmse_m": Metric("RPE RMSE, one step", "cm", 100.0, 2),
    "map_error_m": Metric("map error (mean point-to-wall)", "cm", 100.0, 1),
    "map_coverage": Metric("map coverage (walls within 0.3 m)", "%", 100.0, 1),
    "map_points_occupied": Metric("map points on occupied cells", "%", 100.0, 1),
    "map_points_free": Metric("map points on free cells", "%", 100.0, 1),
    "map_error_3d_m": Metric("3D map error (median to the surfaces)", "cm", 100.0, 1),
    "ranging_rmse_m": Metric("ranging RMSE (specular points)", "mm", 1000.0, 1),
    "ranging_points": Metric("ranging points", "", 1.0, 0),
    "poses": Metric("poses", "", 1.0, 0),
    "points_per_scan": Metric("points per scan", "", 1.0, 1),
    "loop_closures": Metric("loop closures", "", 1.0, 0),
    "tracking_lost": Metric("tracking lost"),
    "status_counts": Metric("scan statuses"),
    "lost_scans": Metric("lost scans"),
    "slam_ms_per_scan": Metric("SLAM time per scan (median)", "ms", 1.0, 1),
    "height_error": Metric("heights on horizontal surfaces"),
    "timings_s": Metric("seconds per stage"),
}


def format_value(key: str, value: object) -> tuple[str, str]:
    """(text, unit) of one metric's value."""
    spec = METRICS.get(key, Metric(key))
    if value is None:
        return "—", ""
    if isinstance(value, bool):
        return ("yes" if value else "no"), ""
    if isinstance(value, (int, float)):
        return f"{value * spec.scale:.{spec.digits}f}", spec.unit
    if key == "status_counts" and isinstance(value, dict):
        return ", ".join(f"{count} {name}" for name, count in value.items() if count) or "none", ""
    if key == "timings_s" and isinstance(value, dict):
        return ", ".join(f"{stage} {seconds:.1f}" for stage, seconds in value.items()), "s"
    if key == "height_error" and isinstance(value, dict):
        if not value.get("points"):
            return "no point", ""
        return (f"{value['points']} points: median |Δz| {value['median_abs_m'] * 100:.1f}, "
                f"p90 {value['p90_abs_m'] * 100:.1f}, bias {value['bias_m'] * 100:+.1f}"), "cm"
    if isinstance(value, list):
        return (", ".join(map(str, value)) if value else "none"), ""
    return str(value), ""


def metric_rows(metrics: dict) -> list[tuple[str, str, str]]:
    """(name, value, unit) of every metric, in metrics.json's order."""
    return [(METRICS.get(key, Metric(key)).label, *format_value(key, value)) for key, value in metrics.items()]
