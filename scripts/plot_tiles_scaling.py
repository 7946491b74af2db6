#!/usr/bin/env python3
"""Expected wall time of a map fused in tiles on N Dask workers, from measured task times.

    lidarsurf fuse DRIVE -o tiles.ply --tile-size 100 --threads 1 --json tiles.json
    lidarsurf fuse DRIVE -o whole.ply --threads 1 --json whole.json
    scripts/plot_tiles_scaling.py tiles.json [more.json ...] --whole whole.json -o scaling.png

A report of `fuse --tile-size` run on one thread holds what each task of lidarsurf.fuse_tiles does
on a single-threaded worker: the plan's pass over the scans (`seconds.plan`, cut into tasks of
PLAN_CHUNK scans, as fuse_tiles cuts it) and one pass per group of tiles (`per_group[].seconds`).
The plan's tasks run first, all of them before any group (the plan needs every scan's reach); the
groups then have no dependency on one another and are handed to the first free worker in the
plan's order, as the scheduler does. Scheduler and transfer overheads are left out: the times are
a lower bound of what a cluster gives. Prints a table per report and where more workers stop
helping: the last doubling that still cuts the time by 10 %, and the bound of the longest task.
"""
import argparse
import heapq
import json
import math
import sys

WORKERS = (1, 2, 4, 8, 16, 64)
PLAN_CHUNK = 100  # scans per plan task (fuse_tiles' plan_chunk)


def list_schedule(tasks, workers):
    """Makespan of `tasks` (seconds) handed in order to the first free of `workers`."""
    free = [0.0] * workers
    for t in tasks:
        heapq.heapreplace(free, free[0] + t)
    return max(free)


def expected(report, workers):
    frames = report["frames"]
    chunks = max(1, math.ceil(frames / PLAN_CHUNK))
    plan = list_schedule([report["seconds"]["plan"] / chunks] * chunks, workers)
    groups = [g["seconds"] for g in report["per_group"]]
    return plan + list_schedule(groups, workers), plan


def label(report):
    return f"{report['frames']} scans, tiles of {report['tile_size']:g} m, groups of {report['tile_group']}"


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("reports", nargs="+", help="`fuse --tile-size ... --threads 1 --json` reports")
    p.add_argument("--whole", help="the report of the same drive fused whole (`fuse --json`), drawn as a line")
    p.add_argument("-o", "--output", help="the plot (.png); without it, the tables only")
    a = p.parse_args(argv)
    reports = []
    for path in a.reports:
        with open(path) as f:
            r = json.load(f)
        if "per_group" not in r:
            sys.exit(f"{path}: not a report of `fuse --tile-size` (no per_group)")
        reports.append(r)
    whole = None
    if a.whole:
        with open(a.whole) as f:
            w = json.load(f)
        whole = sum(v for k, v in w["seconds"].items() if k != "total")  # its stages, read to write
    curves = []
    for r in reports:
        tasks = r["per_group"]
        work = r["seconds"]["plan"] + sum(g["seconds"] for g in tasks)
        longest = max(g["seconds"] for g in tasks)
        print(f"## {label(r)}: {len(tasks)} group tasks, {work:.1f} s of tasks in all, the longest {longest:.1f} s")
        if whole:
            print(f"fused whole on one thread: {whole:.1f} s; the tasks take {work / whole:.2f} times that")
        print("| workers | expected wall | of which the plan | speed-up |")
        print("|---|---|---|---|")
        walls = []
        for n in WORKERS:
            wall, plan = expected(r, n)
            walls.append(wall)
            print(f"| {n} | {wall:.1f} s | {plan:.1f} s | {walls[0] / wall:.1f}x |")
        stop = None
        for (n0, w0), w1 in zip(zip(WORKERS, walls), walls[1:]):
            if w1 > 0.9 * w0:  # the next step up cuts less than 10 %
                stop = n0
                break
        if stop:
            print(f"more workers stop helping past about {stop} ({len(tasks)} tasks; the longest, {longest:.1f} s, bounds the wall time)\n")
        else:
            print(f"still helping at {WORKERS[-1]} workers ({len(tasks)} tasks; the longest, {longest:.1f} s, bounds the wall time)\n")
        curves.append((label(r), walls))
    if a.output:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(7, 4.5))
        for name, walls in curves:
            ax.plot(WORKERS, walls, marker="o", label=name)
        if whole:
            ax.axhline(whole, color="grey", linestyle="--", label="fused whole, one thread")
        ax.set_xscale("log", base=2)
        ax.set_yscale("log")
        ax.set_xticks(WORKERS)
        ax.set_xticklabels([str(n) for n in WORKERS])
        ax.set_xlabel("single-threaded Dask workers")
        ax.set_ylabel("expected wall time (s)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(a.output, dpi=120)
        print(f"-> {a.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
