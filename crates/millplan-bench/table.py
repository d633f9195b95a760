#!/usr/bin/env python3
"""The benchmark table of docs/benchmarks.md, measured on this machine.

Builds the release binaries, writes the large inputs (`gen-inputs`) into a
folder unless they are there, runs every workload five times in turn (the
peers in the same round, so that they meet the same load), and writes the
median wall time and the median peak resident set size (`/usr/bin/time -f
%M`) of each, with the gate's instruction counts from
crates/millplan-bench/gate-baseline.toml, between the markers
`<!-- bench-table:start -->` and `<!-- bench-table:end -->` of
docs/benchmarks.md.

Usage: crates/millplan-bench/table.py [INPUT-DIR] [--runs N] [--no-build]
The peers need Python 3 with NumPy and SciPy (pip install numpy scipy).
"""
import argparse
import os
import platform
import re
import statistics
import subprocess
import sys
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
TARGET = os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target"))
BIN = os.path.join(TARGET, "release")
PEERS = os.path.join(ROOT, "crates", "millplan-bench", "peers")
START, END = "<!-- bench-table:start -->", "<!-- bench-table:end -->"

TRUNNION = """name = "bench A/C trunnion"
[spindle]
min = 500.0
max = 18000.0
accel = 6000.0
[feed]
min = 1.0
max = 20000.0
rapid = 40000.0
[kinematics]
kind = "table-ac"
rot_point = [0.0, 0.0, -100.0]
[kinematics.first]
min = -120.0
max = 120.0
sign = 1.0
[kinematics.second]
sign = 1.0
[axes.a]
velocity = 9000.0
[axes.c]
velocity = 18000.0
"""


def workloads(d):
    mp = os.path.join(BIN, "millplan")
    return [
        # (name, what, goal, command, gate workload, peer of)
        ("speed", "`speed`, 1,002,729 points on 2,000,000 triangles", "≤ 1.4 s, ≤ 0.40 GB",
         [mp, "speed", "--stl", f"{d}/big.stl", f"{d}/raster_1m.apt", "--vc", "63", "--fz", "0.125",
          "--ap", "0.3", "-o", f"{d}/out_speed.apt", "-q"], "speed", None),
        ("speed-peer", "Python peer of `speed` (NumPy/SciPy k-d tree, nearest centre)", "",
         [sys.executable, f"{PEERS}/speed_peer.py", f"{d}/big.stl", f"{d}/raster_1m.apt",
          f"{d}/out_peer.apt"], None, "speed"),
        ("inspect", "`inspect --json`, 1,000,000 GOTOs", "≥ 5× the regex scan, ≤ 80 MB",
         [mp, "inspect", "--json", f"{d}/big.apt"], "inspect", None),
        ("inspect-peer", "Python regex scan of the same file", "",
         [sys.executable, f"{PEERS}/inspect_peer.py", f"{d}/big.apt"], None, "inspect"),
        ("post", "`post --g93`, 1,001,002 CL points, A/C trunnion", "≤ 3 s, ≤ 0.6 GB",
         [mp, "post", f"{d}/five_axis_1m.apt", "--machine", f"{d}/trunnion.toml", "--g93",
          "-o", f"{d}/out_post.nc", "-q"], "post", None),
        ("access", "`setup --tool 10,40,40,60`, 98,568 triangles × 1,280 icosphere cells", "≤ 15 s",
         [mp, "setup", "--type", "ca", "--stl", f"{d}/access_98k.stl", "--tool", "10,40,40,60", "--grid",
          "icosphere", "--cells", "1280", "--json", "-q"], "access", None),
        ("optimise", "`optimise --passes speed,feed`, 100,006 ball-end moves, offset stock at 0.1 mm, with its checks",
         "≤ 15 s",
         [mp, "optimise", f"{d}/r100k.apt", "--stl", f"{d}/demo/part.stl", "--stock", "offset:0.3",
          "--machine", f"{d}/demo/machine.toml", "--material", "al7075", "--passes", "speed,feed",
          "-o", f"{d}/out_optimise.nc", "-q"], None, None),
    ]


def run_once(cmd):
    t = time.monotonic()
    p = subprocess.run(["/usr/bin/time", "-f", "%M"] + cmd, stdout=subprocess.DEVNULL,
                       stderr=subprocess.PIPE, text=True)
    wall = time.monotonic() - t
    if p.returncode not in (0, 3):
        sys.exit(f"{' '.join(cmd)}: exit {p.returncode}\n{p.stderr}")
    rss_kb = int(p.stderr.strip().splitlines()[-1])
    return wall, rss_kb * 1024


def gate_counts():
    counts = {}
    path = os.path.join(ROOT, "crates", "millplan-bench", "gate-baseline.toml")
    if not os.path.exists(path):
        return counts
    for line in open(path):
        m = re.match(r"^(\w+) = ([0-9_]+)", line)
        if m:
            counts[m.group(1)] = int(m.group(2).replace("_", ""))
    return counts


def prepare(d, build):
    if build:
        subprocess.run(["cargo", "build", "--release", "-q", "-p", "millplan", "-p", "millplan-bench",
                        "--bins", "--examples"], cwd=ROOT, check=True)
    if not os.path.exists(f"{d}/five_axis_1m.apt"):
        subprocess.run([os.path.join(BIN, "gen-inputs"), d], check=True)
    if not os.path.exists(f"{d}/access_98k.stl"):
        subprocess.run([os.path.join(BIN, "gen-inputs"), "--access", f"{d}/access_98k.stl"], check=True)
    mp = os.path.join(BIN, "millplan")
    if not os.path.exists(f"{d}/demo/part.stl"):
        subprocess.run([mp, "demo", "-o", f"{d}/demo", "-q"], check=True)
    if not os.path.exists(f"{d}/r100k.apt"):
        subprocess.run([mp, "raster", "--stl", f"{d}/demo/part.stl", "--tool", "ball:10", "--stepover", "0.19",
                        "--step", "0.19", "--tol", "0", "-o", f"{d}/r100k.apt", "-q"], check=True)
    with open(f"{d}/trunnion.toml", "w") as f:
        f.write(TRUNNION)


def size(b):
    return f"{b / 1e9:.2f} GB" if b >= 1e9 else f"{b / 1e6:.0f} MB"


def render(rows, results, counts, runs):
    host = f"{platform.node()}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f} at the end"
    out = [START, "",
           f"Measured by `crates/millplan-bench/table.py` on {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())} "
           f"({host}): median of {runs} runs each, the peers in the same rounds; peak RSS by "
           "`/usr/bin/time -f %M`; instructions from the gate's baseline (reduced workloads, one thread).", "",
           "| work | wall (median) | peak RSS | goal | vs peer | gate instructions |",
           "|---|---|---|---|---|---|"]
    for name, what, goal, _, gate, peer_of in rows:
        walls, rss = results[name]
        w = statistics.median(walls)
        ratio = ""
        peer = next((r[0] for r in rows if r[5] == name), None)
        if peer:
            ratio = f"{statistics.median(results[peer][0]) / w:.1f}× faster"
        count = f"{counts[gate]:,}" if gate in counts else ""
        out.append(f"| {what} | {w:.2f} s ({min(walls):.2f}–{max(walls):.2f}) | {size(statistics.median(rss))} "
                   f"| {goal} | {ratio} | {count} |")
    out += ["", END]
    return "\n".join(out)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dir", nargs="?", default="/tmp/millplan-bench-inputs")
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--no-build", action="store_true")
    ap.add_argument("--only", default="")
    a = ap.parse_args()
    os.makedirs(a.dir, exist_ok=True)
    prepare(a.dir, not a.no_build)
    rows = workloads(a.dir)
    if a.only:
        keep = a.only.split(",")
        rows = [r for r in rows if r[0] in keep or r[5] in keep]
    results = {r[0]: ([], []) for r in rows}
    for i in range(a.runs):
        for name, _, _, cmd, _, _ in rows:
            wall, rss = run_once(cmd)
            results[name][0].append(wall)
            results[name][1].append(rss)
            print(f"run {i + 1}: {name} {wall:.2f} s {size(rss)}", file=sys.stderr)
    table = render(rows, results, gate_counts(), a.runs)
    print(table)
    doc = os.path.join(ROOT, "docs", "benchmarks.md")
    text = open(doc).read()
    if START in text and END in text:
        text = text[: text.index(START)] + table + text[text.index(END) + len(END):]
    else:
        text = text.rstrip("\n") + "\n\n" + table + "\n"
    open(doc, "w").write(text)


if __name__ == "__main__":
    main()
