#!/usr/bin/env python3
"""Draws time and memory per scan over a fused drive from `lidarsurf fuse --json` reports.

usage: plot_fuse_report.py OUT_PNG REPORT_JSON[=LABEL] [REPORT_JSON[=LABEL] ...]
  top:    integrate time per scan (insert + carving), ms: each scan (dots) and the median of 25
  middle: voxels in the grid
  bottom: resident memory, MiB
"""
import json
import statistics
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def running_median(values, width=25):
    half = width // 2
    return [statistics.median(values[max(0, i - half):i + half + 1]) for i in range(len(values))]


def main(argv):
    if len(argv) < 3:
        sys.exit(__doc__)
    out = argv[1]
    fig, axes = plt.subplots(3, 1, figsize=(9, 9), sharex=True)
    for spec in argv[2:]:
        path, _, label = spec.partition("=")
        with open(path) as f:
            report = json.load(f)
        rows = report["per_frame"]
        label = label or path
        n = list(range(len(rows)))
        ms = [r["integrate_ms"] for r in rows]
        dots = axes[0].plot(n, ms, ".", markersize=2, alpha=0.3)
        axes[0].plot(n, running_median(ms), color=dots[0].get_color(),
                     label=f"{label}: median {statistics.median(ms):.1f} ms")
        axes[1].plot(n, [r["voxels"] / 1e6 for r in rows], label=label)
        axes[2].plot(n, [r["resident_mib"] for r in rows],
                     label=f"{label}: peak {report.get('peak_resident_mib', 0):.0f} MiB")
    axes[0].set_ylabel("integrate per scan (ms)")
    axes[1].set_ylabel("voxels (millions)")
    axes[2].set_ylabel("resident memory (MiB)")
    axes[2].set_xlabel("scan")
    finish(fig, axes, out)


def finish(fig, axes, out):
    """Grids and legends on every panel, then the figure to `out`."""
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=90)


if __name__ == "__main__":
    main(sys.argv)
