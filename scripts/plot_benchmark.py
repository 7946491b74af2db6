#!/usr/bin/env python3
"""Draws the paper's Fig. 6 from `lidarsurf benchmark`'s results.json.

usage: plot_benchmark.py RESULTS_JSON OUT_DIR
  fig6a_range.png  average error P->GT against range (Fig. 6a)
  fig6b_delta.png  share of vertices within delta of the ground truth (Fig. 6b)
"""
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HIGHLIGHT = {"AN+GC kmax=5": ("tab:blue", 2.5), "IMLS": ("tab:red", 2.5)}


def style(name):
    colour, width = HIGHLIGHT.get(name, (None, 1.0))
    return {"color": colour, "linewidth": width, "alpha": 1.0 if name in HIGHLIGHT else 0.6}


def main(argv):
    if len(argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    with open(argv[1]) as f:
        res = json.load(f)
    out = argv[2]
    title = f"{res['dataset']} ({res['frames']} frames)"

    fig, ax = plt.subplots(figsize=(6, 4))
    for m in res["methods"]:
        bins = [b for b in m["by_range"] if b["count"] > 0 and b["ae"] is not None]
        if not bins:
            continue
        ax.plot([0.5 * (b["lo"] + b["hi"]) for b in bins], [b["ae"] for b in bins], marker="o", markersize=3,
                label=m["name"], **style(m["name"]))
    ax.set_xlabel("range (m)")
    ax.set_ylabel("average error P->GT (m)")
    ax.set_title("Fig. 6a " + title, fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "fig6a_range.png"), dpi=120)

    fig, ax = plt.subplots(figsize=(6, 4))
    for m in res["methods"]:
        if m["frames"] == 0:
            continue
        ax.plot(m["curve"]["delta"], [100 * s for s in m["curve"]["share"]], label=m["name"], **style(m["name"]))
    ax.set_xlabel("delta (m)")
    ax.set_ylabel("vertices with P->GT error <= delta (%)")
    ax.set_title("Fig. 6b " + title, fontsize=9)
    ax.set_ylim(0, 100)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "fig6b_delta.png"), dpi=120)
    print(f"figures: {os.path.join(out, 'fig6a_range.png')}, {os.path.join(out, 'fig6b_delta.png')}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
