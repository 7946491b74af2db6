#!/usr/bin/env python3
"""Time and memory of a map fused in tiles, from `lidarsurf fuse --tile-size ... --json REPORT`:
per tile, in the order they ran, the resident memory after it and its time, and the running total.

    scripts/plot_tiles.py REPORT.json OUT.png
"""
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(report, out):
    with open(report) as f:
        r = json.load(f)
    tiles = r["per_tile"]
    n = range(1, len(tiles) + 1)
    seconds = [t["ms"] / 1e3 for t in tiles]
    total = [sum(seconds[:i]) / 60 for i in n]
    fig, (mem, time) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    mem.plot(n, [t["resident_mib"] for t in tiles], color="tab:blue")
    mem.axhline(r["peak_resident_mib"], color="tab:red", linestyle="--", label=f"peak {r['peak_resident_mib']:.0f} MiB")
    mem.set_ylabel("resident after the tile (MiB)")
    mem.set_ylim(bottom=0)
    mem.legend(loc="lower right")
    mem.set_title(f"{r['frames']} scans in {r['tiles']} tiles of {r['tile_size']:g} m: "
                  f"{r['mesh_triangles'] / 1e6:.1f} M triangles in {r['seconds']['total'] / 60:.0f} min")
    time.bar(n, seconds, color="tab:gray", label="the tile (s)")
    time.set_ylabel("seconds per tile")
    time.set_xlabel("tile, in the order fused")
    run = time.twinx()
    run.plot(n, total, color="tab:green")
    run.set_ylabel("running total (min)", color="tab:green")
    run.set_ylim(bottom=0)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
