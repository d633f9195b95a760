#!/usr/bin/env bash
# The Python package's benchmarks against the Rust it wraps, back to back,
# for a quiet machine, ending in one table (Markdown, for docs/python.md):
#
#   (a) working_diameter over 1,000,000 cases vs the model's own loop
#       (millplan-bench's wd_rate example), one rayon thread and all;
#   (b) Mesh.closest_points for the ball centres of a 1,000,000-point
#       raster on the demo part vs the contact phase of `millplan speed
#       --timings` on the same files;
#   (c) the demo's 6 finishing programs optimised (speed, feed) one after another in
#       one process vs on a Dask LocalCluster of 2 workers x 1 thread,
#       RAYON_NUM_THREADS=1.
#
# Usage: bench/quiet.sh MILLPLAN WD_RATE [PYTHON]
#   MILLPLAN  the release binary (cargo build --release -p millplan)
#   WD_RATE   the release example (cargo build --release -p millplan-bench
#             --example wd_rate: target/release/examples/wd_rate)
#   PYTHON    a Python with the release wheel, numpy, pandas and
#             dask[distributed] installed (default: python3)
#
# About 2 minutes on a quiet 2-core machine, most of it (c); 4 minutes at
# load 12-14. The load
# average before and after each part is in the table: above about 0.5 per
# core the figures say more about the other work than about millplan.
set -euo pipefail

MILLPLAN=${1:?usage: quiet.sh MILLPLAN WD_RATE [PYTHON]}
WD_RATE=${2:?usage: quiet.sh MILLPLAN WD_RATE [PYTHON]}
PY=${3:-python3}
HERE=$(cd "$(dirname "$0")" && pwd)
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
load() { cut -d' ' -f1 /proc/loadavg; }
T0=$(date +%s)
TIMEFORMAT='%R %U %S'

"$MILLPLAN" demo -o "$W/demo" -q
"$PY" -c 'import millplan, sys; print("millplan from", millplan.__file__, file=sys.stderr)'

echo "(a) working diameter" >&2
echo "load_a $(load)" >"$W/loads"
"$WD_RATE" >"$W/wd_rate"
# CPU: wd_rate's 10 passes (5 serial, 5 through rayon) and its cases, on one thread.
{ time RAYON_NUM_THREADS=1 "$WD_RATE" >/dev/null; } 2>"$W/wd_rate_time"
RAYON_NUM_THREADS=1 "$PY" "$HERE/bench.py" gil >"$W/wd_gil"
RAYON_NUM_THREADS=1 "$PY" "$HERE/bench.py" wd >"$W/wd_py1"
"$PY" "$HERE/bench.py" wd >"$W/wd_pyn"

echo "(b) closest points" >&2
echo "load_b $(load)" >>"$W/loads"
"$PY" "$HERE/bench.py" raster "$W/demo/part.stl" "$W/r1m.apt" >"$W/raster"
"$PY" "$HERE/bench.py" closest "$W/demo/part.stl" "$W/r1m.apt" >"$W/closest"
{ time "$MILLPLAN" speed "$W/r1m.apt" --stl "$W/demo/part.stl" -o "$W/r1m-speed.apt" \
    --vc 63 --fz 0.125 --ap 0.3 --timings -q >/dev/null 2>"$W/speed_timings"; } 2>"$W/speed_time"

echo "(c) Dask batch" >&2
echo "load_c $(load)" >>"$W/loads"
mkdir "$W/batch"
cp "$W"/demo/finish* "$W/batch/" # finish.apt and its 5 G-code versions
RAYON_NUM_THREADS=1 "$PY" "$HERE/bench.py" batch "$W/batch" "$W/demo/part.stl" \
    "$W/demo/machine.toml" >"$W/batch_out"
echo "load_end $(load)" >>"$W/loads"
echo "total $(($(date +%s) - T0))" >>"$W/loads"

"$PY" - "$W" <<'EOF'
import re, sys, pathlib
w = pathlib.Path(sys.argv[1])
t = lambda n: (w / n).read_text()
num = lambda pat, text: float(re.search(pat, text).group(1))
loads = dict(l.split() for l in t("loads").splitlines())
r = t("wd_rate")
rust1, rustn = num(r"1 thread ([\d.]+) s", r), num(r"threads ([\d.]+) s", r)
nthreads = re.search(r"; (\d+) threads", r).group(1)
_, ru, rs = map(float, t("wd_rate_time").split())
rust_cpu = (ru + rs) / 10
g = t("wd_gil")
py_cpu, pace = num(r"cases: ([\d.]+) s CPU", g), num(r"runs at ([\d.]+) of its pace", g)
py1, pyn = num(r"cases: ([\d.]+) s", t("wd_py1")), num(r"cases: ([\d.]+) s", t("wd_pyn"))
c = t("closest")
cwall, ccpu, npts = num(r"points ([\d.]+) s wall", c), num(r"([\d.]+) s CPU", c), num(r"; (\d+) points", c)
st = t("speed_timings")
contact = sum(map(float, re.findall(r"([\d.]+) s  contact and working diameter", st)))
swall, su, ss = map(float, t("speed_time").split())
b = t("batch_out")
one, two, nprog = num(r"one process ([\d.]+) s", b), num(r"1 thread ([\d.]+) s", b), num(r"(\d+) programs", b)
warm, start = num(r"warm ([\d.]+) s", b), num(r"its start took ([\d.]+) s", b)
rows = [
    ("(a) `working_diameter`, 1,000,000 cases, 1 thread, CPU: one Python call vs one pass of `wd_rate`",
     f"{py_cpu:.3f} s vs {rust_cpu:.3f} s (a tenth of its {ru + rs:.2f} s for 10 passes and building "
     f"the cases once): about {100 * rust_cpu / py_cpu:.0f} % of the Rust throughput", loads["load_a"]),
    ("(a) a Python loop beside that call", f"{pace:.2f} of its pace alone (0: the GIL held)", loads["load_a"]),
    ("(a) the same, wall time, best of 5",
     f"{py1:.4f} s vs {rust1:.4f} s: {100 * rust1 / py1:.0f} % of the Rust throughput", loads["load_a"]),
    (f"(a) the same, {nthreads} threads", f"{pyn:.4f} s vs {rustn:.4f} s: {100 * rustn / pyn:.0f} %", loads["load_a"]),
    (f"(b) `Mesh.closest_points`, {npts:,.0f} ball centres (demo part)",
     f"{cwall:.3f} s wall, {ccpu:.3f} s CPU (best of 3)", loads["load_b"]),
    ("(b) `millplan speed --timings`, same files: contact and working diameter",
     f"{contact:.3f} s wall (Python's closest points: {100 * cwall / contact:.0f} % of it); "
     f"whole run {swall:.1f} s wall, {su + ss:.1f} s CPU", loads["load_b"]),
    (f"(c) {nprog:.0f} programs (speed, feed), RAYON_NUM_THREADS=1: one process vs Dask 2 workers x 1 thread",
     f"{one:.1f} s vs {two:.1f} s: {one / two:.2f}x (the cluster's start included)", loads["load_c"]),
    ("(c) the same on a running cluster (started, millplan imported in each worker, before the clock)",
     f"{one:.1f} s vs {warm:.1f} s: {one / warm:.2f}x (the start took {start:.1f} s)", loads["load_c"]),
]
print("| what | figure | load (1 min) |\n|---|---|---|")
for what, fig, load in rows:
    print(f"| {what} | {fig} | {load} |")
print(f"\nload at the end {loads['load_end']}; the whole script {loads['total']} s")
EOF
