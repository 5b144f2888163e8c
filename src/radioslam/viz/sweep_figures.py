"""A sweep's standard plots (issue #14), from its table (one row per run):

- ``ate_vs_snr.png``: ATE against SNR, the median and the 10–90 % quantile band per scene (and variant);
- ``ranging_vs_crb.png``: the ranging RMSE of specular echoes against the Cramér–Rao bound at the
  run's SNR (:mod:`radioslam.eval.crb`; Kay, *Fundamentals of Statistical Signal Processing I*, §3.11);
- ``success_by_motion.png``: the share of runs with ATE ≤ 0.2 m per motion class (generated cases).

A plot whose columns the table lacks (one SNR only, no generated case) is not drawn.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from radioslam.config import RadioConfig  # noqa: E402
from radioslam.eval.crb import range_crb_m  # noqa: E402
from radioslam.io.atomic import atomic_path  # noqa: E402

SUCCESS_M = 0.2  # ATE of a successful run (the robustness benchmark's)


def save_figure(fig, path: Path) -> None:
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=130, bbox_inches="tight")
    plt.close(fig)


def _groups(ok: pd.DataFrame):
    keys = ["scene", "variant"] if ok["variant"].nunique() > 1 else ["scene"]
    for key, group in ok.groupby(keys, sort=True):
        yield " / ".join(str(k) for k in (key if isinstance(key, tuple) else (key,)) if k), group


def ate_vs_snr(ok: pd.DataFrame, path: Path) -> bool:
    if ok["snr_db"].nunique() < 2 or "ate_rmse_m" not in ok:
        return False
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for label, group in _groups(ok):
        stats = group.groupby("snr_db")["ate_rmse_m"].quantile([0.1, 0.5, 0.9]).unstack()
        ax.plot(stats.index, stats[0.5], marker="o", label=label)
        ax.fill_between(stats.index, stats[0.1], stats[0.9], alpha=0.2)
    ax.set(xlabel="SNR (dB)", ylabel="ATE RMSE (m)", title="ATE against SNR: median, 10–90 % band",
           yscale="log" if (ok["ate_rmse_m"] > 0).all() else "linear")
    ax.legend(fontsize=8, loc="upper right")
    save_figure(fig, path)
    return True


def ranging_vs_crb(ok: pd.DataFrame, path: Path) -> bool:
    if "ranging_rmse_m" not in ok or not ok["ranging_rmse_m"].notna().any():
        return False
    radio = RadioConfig()  # the default numerology (a sweep that overrides it: the bound is the default's)
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    snr = np.linspace(ok["snr_db"].min() - 3, ok["snr_db"].max() + 3, 50)
    symbols = radio.symbols_per_frame * radio.frames
    ax.plot(snr, range_crb_m(radio.n_subcarriers, radio.subcarrier_spacing_hz, symbols, snr), "k--",
            label="Cramér–Rao bound, one path")
    for label, group in _groups(ok):
        ax.scatter(group["snr_db"], group["ranging_rmse_m"], s=14, label=label)
    ax.set(xlabel="SNR (dB)", ylabel="ranging RMSE (m)", yscale="log",
           title="ranging RMSE of specular echoes against the CRB")
    ax.legend(fontsize=8)
    save_figure(fig, path)
    return True


def success_by_motion(table: pd.DataFrame, path: Path) -> bool:
    if "motion" not in table or not table["motion"].notna().any():
        return False
    cases = table[table["motion"].notna()]
    success = cases.assign(ok=(cases["status"] == "ok") & (cases.get("ate_rmse_m", np.inf) <= SUCCESS_M))
    share = success.groupby("motion")["ok"].agg(["mean", "size"])
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    ax.bar(share.index, 100 * share["mean"])
    for x, (mean, size) in enumerate(share.itertuples(index=False)):
        ax.text(x, 100 * mean + 1, f"{100 * mean:.0f} % of {size}", ha="center", fontsize=8)
    ax.set(ylabel=f"runs with ATE ≤ {SUCCESS_M} m (%)", ylim=(0, 115), title="success rate per motion class")
    ax.tick_params(axis="x", labelrotation=30)
    save_figure(fig, path)
    return True


def sweep_figures(table: pd.DataFrame, out: Path) -> list[Path]:
    """The plots the table has columns for, under ``out``; their paths."""
    ok = table[table["status"] == "ok"]
    drawn = []
    for name, draw, data in (("ate_vs_snr.png", ate_vs_snr, ok), ("ranging_vs_crb.png", ranging_vs_crb, ok),
                             ("success_by_motion.png", success_by_motion, table)):
        if len(data) and draw(data, Path(out) / name):
            drawn.append(Path(out) / name)
    return drawn
