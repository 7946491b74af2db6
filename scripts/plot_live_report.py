#!/usr/bin/env python3
"""Draws the live mesh's latency and staleness over a drive from `lidarsurf fuse --live --json`.

usage: plot_live_report.py OUT_PNG LIVE_JSON [BATCH_JSON]
  top:    time per scan, ms: live update_ms (integrate + carve + live-mesh update) and, with a
          batch report (`fuse --json` without --live) of the same drive, its integrate_ms; each
          scan (dots) and the median of 25
  middle: triangles the live mesh changed per scan (delta) and holds (live)
  bottom: with --live-check-every: the share of the live area within 30 m farther than 5 cm from
          the exact mesh (staleness), and the share of the exact area the live mesh covers
"""
import json
import statistics
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from plot_fuse_report import finish, running_median  # noqa: E402


def load(path):
    with open(path) as f:
        return json.load(f)


def main(argv):
    if len(argv) not in (3, 4):
        sys.exit(__doc__)
    live = load(argv[2])
    rows = live["per_frame"]
    n = list(range(len(rows)))
    fig, axes = plt.subplots(3, 1, figsize=(9, 9), sharex=True)
    series = [("live update (integrate + carve + mesh)", [r["update_ms"] for r in rows])]
    if len(argv) == 4:
        series.append(("batch fuse (integrate + carve)", [r["integrate_ms"] for r in load(argv[3])["per_frame"]]))
    for label, ms in series:
        dots = axes[0].plot(range(len(ms)), ms, ".", markersize=2, alpha=0.3)
        p90 = sorted(ms)[int(0.9 * (len(ms) - 1))]
        axes[0].plot(range(len(ms)), running_median(ms), color=dots[0].get_color(),
                     label=f"{label}: median {statistics.median(ms):.1f} ms, p90 {p90:.1f} ms")
    axes[0].axhline(100, color="grey", linestyle="--", linewidth=0.8)
    axes[0].set_ylabel("time per scan (ms)")
    axes[1].plot(n, [r["delta_triangles"] / 1e3 for r in rows], ".", markersize=2, label="triangles in the delta (thousands)")
    axes[1].plot(n, [r["live_triangles"] / 1e6 * 100 for r in rows], label="live mesh (100 thousands)")
    axes[1].set_ylabel("triangles")
    checks = [(i, r["staleness"]) for i, r in enumerate(rows) if "staleness" in r]
    if checks:
        axes[2].plot([i for i, _ in checks], [100 * s["share"] for _, s in checks], "o-", markersize=3,
                     label="stale: live area > 5 cm from the exact mesh (%)")
        axes[2].plot([i for i, _ in checks], [100 * (1 - s["covered_share"]) for _, s in checks], "s-", markersize=3,
                     label="not yet meshed: exact area the live mesh lacks (%)")
        axes[2].axhline(2, color="grey", linestyle="--", linewidth=0.8)
    axes[2].set_ylabel("within 30 m (%)")
    axes[2].set_xlabel("scan")
    finish(fig, axes, argv[1])


if __name__ == "__main__":
    main(sys.argv)
