"""The memory budget of `lidarsurf reconstruct` against the kernel's count of its peak.

The oracle is the child's peak resident memory as the kernel reports it (os.wait4's ru_maxrss),
not the program's own output. docs/reliability.md promises an estimate within 0.9-1.4x of that
peak; a budget a little below the estimate is refused (exit 5) before the extraction, and a run at
a budget equal to its estimate stays within budget / 0.9. The scans: layers stacked 1.5 and 3
voxels apart (dense blocks, where a per-block estimate fell to half the peak), and the simulator's
town frame (a sparse single scan). Not run under the sanitizers (their allocators change the peak).

Usage: test_memory_budget.py LIDARSURF_CLI  (or --write PATH LAYERS GAP SIDE STEP SEED: one scan)
"""
import os
import re
import subprocess
import sys
import tempfile

import numpy as np

failures = []


def stacked_layers(path, layers, gap, side, step, seed):
    """`layers` horizontal squares of `side` m, `gap` m apart, a point every `step` m (jittered)."""
    rng = np.random.default_rng(seed)
    g = np.arange(-side / 2, side / 2, step)
    x, y = (a.ravel() for a in np.meshgrid(g, g))
    parts = []
    for i in range(layers):
        z = -1.7 + i * gap + 0.01 * rng.standard_normal(x.size)
        jx, jy = (0.3 * step * rng.standard_normal(x.size) for _ in range(2))
        parts.append(np.stack([x + jx, y + jy, z, np.full(x.size, 0.5)], 1))
    np.concatenate(parts).astype(np.float32).tofile(path)


def write_stacked_layers(path, *args):
    """stacked_layers in a child process: the arrays would stay in this one's memory, and a child
    forked from it starts with its resident pages (ru_maxrss would count them)."""
    subprocess.run([sys.executable, __file__, "--write", path] + [str(a) for a in args], check=True)


def run(args):
    """(exit code, output, peak resident MiB) of the CLI with `args`."""
    p = subprocess.Popen([CLI] + args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    out = p.stdout.read()
    _, status, usage = os.wait4(p.pid, 0)
    p.returncode = os.waitstatus_to_exitcode(status)
    return p.returncode, out, usage.ru_maxrss / 1024.0


def check(what, ok, detail):
    print(("ok   " if ok else "FAIL ") + what + ": " + detail)
    if not ok:
        failures.append(what)


if sys.argv[1] == "--write":
    path, layers, gap, side, step, seed = sys.argv[2:8]
    stacked_layers(path, int(layers), float(gap), float(side), float(step), int(seed))
    sys.exit(0)
CLI = sys.argv[1]

with tempfile.TemporaryDirectory() as d:
    scans = {}
    scans["30 layers 1.5 voxels apart"] = os.path.join(d, "layers30.bin")
    write_stacked_layers(scans["30 layers 1.5 voxels apart"], 30, 0.3, 24, 0.1, 1)
    scans["10 layers 3 voxels apart"] = os.path.join(d, "layers10.bin")
    write_stacked_layers(scans["10 layers 3 voxels apart"], 10, 0.6, 36, 0.08, 2)
    town = os.path.join(d, "town")
    code, out, _ = run(["simulate", "--scene", "town", "--frames", "1", "--gt-beams", "0", "-o", town])
    assert code == 0, out
    scans["a town frame"] = os.path.join(town, "velodyne", "000000.bin")
    mesh = os.path.join(d, "mesh.ply")
    for name, scan in scans.items():
        code, out, peak = run(["reconstruct", scan, "-o", mesh, "--max-memory-mb", "100000"])
        m = re.search(r"memory estimate (\d+) MiB", out)
        if code != 0 or not m:
            check(name, False, "exit %d: %s" % (code, out[-300:]))
            continue
        estimate = float(m.group(1))
        check(name + ": the estimate is 0.9-1.4x the peak", 0.9 <= estimate / peak <= 1.4,
              "estimate %.0f MiB, peak %.0f MiB (%.2fx)" % (estimate, peak, estimate / peak))
        if peak < 100:
            continue  # below this, the budget's checks are those of test_bad_input.sh
        below = int(estimate * 0.95)
        code, out, peak_refused = run(["reconstruct", scan, "-o", mesh, "--max-memory-mb", str(below)])
        check(name + ": a budget of 0.95x the estimate is refused before the extraction",
              code == 5 and "surface extraction would need" in out and peak_refused < peak,
              "exit %d, peak %.0f MiB" % (code, peak_refused))
        budget = int(estimate) + 1
        code, out, peak_at = run(["reconstruct", scan, "-o", mesh, "--max-memory-mb", str(budget)])
        check(name + ": at a budget equal to the estimate, the peak stays within budget / 0.9",
              code == 0 and peak_at <= budget / 0.9, "exit %d, budget %d MiB, peak %.0f MiB" % (code, budget, peak_at))

if failures:
    print("%d failed" % len(failures))
    sys.exit(1)
print("all passed")
