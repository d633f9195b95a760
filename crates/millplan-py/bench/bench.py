#!/usr/bin/env python3
"""Benchmarks of the Python package against the Rust it wraps.

    python bench.py wd [N]                        # working_diameter over N (1,000,000) cases
    python bench.py closest STL APT [R]           # closest points of the ball centres of APT's cutting moves
    python bench.py batch FOLDER PART MACHINE     # Dask batch on 2 workers x 1 thread vs one process

Compare `wd` with `cargo run --release -p millplan-bench --example wd_rate`
(the same cases), `closest` with the contact phase of `millplan speed
--timings` on the same files, and run `batch` with RAYON_NUM_THREADS=1.
Times are the fastest of a few runs.
"""

import os
import sys
import time

import numpy as np

import millplan


def best_of(reps, f):
    best, out = float("inf"), None
    for _ in range(reps):
        t = time.perf_counter()
        out = f()
        best = min(best, time.perf_counter() - t)
    return best, out


def wd(n=1_000_000):
    """The cases of millplan-bench's wd_rate example, by the same formulas."""
    i = np.arange(n, dtype=np.float64)
    ae = 0.25 + (i * 0.569840290998053) % 1.0
    ae[::10] = np.inf
    alpha = 80.0 * ((i * 0.618033988749895) % 1.0)
    af = -180.0 + 360.0 * ((i * 0.754877666246693) % 1.0)
    side = np.where(np.arange(n) % 2 == 0, "left", "right")
    t, v = best_of(5, lambda: millplan.working_diameter(10.0, 0.3, ae, alpha, af, side))
    print(f"{n} cases: {t:.4f} s ({n / t / 1e6:.2f} M/s, sum {v.sum():.6f}), "
          f"RAYON_NUM_THREADS={os.environ.get('RAYON_NUM_THREADS', 'all')}")


def closest(stl, apt, r=5.0):
    part = millplan.read_stl(stl)
    p = millplan.read_program(apt)
    centres = p.xyz[p.kind == 1] + [0.0, 0.0, float(r)]
    t0 = time.perf_counter()
    part.closest_points(centres[:1])  # builds the tree
    build = time.perf_counter() - t0
    t, (_, d, _) = best_of(3, lambda: part.closest_points(centres, 3 * float(r) + 1.3))
    print(f"{len(part)} triangles, tree {build:.3f} s; {len(centres)} points {t:.3f} s "
          f"({t / len(centres) * 1e6:.2f} µs each), mean distance {np.nanmean(d[np.isfinite(d)]):.6f}")


def batch(folder, part, machine):
    from millplan.batch import optimise_folder, optimise_one, programs_in

    opts = dict(part=part, machine=machine, stock="offset:0.5", material="al7075", tools="ball:10",
                passes="speed,feed", resolution=0.5)
    files = programs_in(folder)
    t = time.perf_counter()
    rows = [optimise_one(f, opts) for f in files]
    one = time.perf_counter() - t
    t = time.perf_counter()
    df = optimise_folder(folder, workers=2, threads_per_worker=1, **opts)
    two = time.perf_counter() - t
    assert [r["verdict"] for r in rows] == list(df["verdict"]), (rows, df)
    print(f"{len(files)} programs: one process {one:.1f} s, Dask 2 workers x 1 thread {two:.1f} s "
          f"(with the cluster's start), {one / two:.2f}x; verdicts {list(df['verdict'])}")


if __name__ == "__main__":
    what, args = sys.argv[1], sys.argv[2:]
    {"wd": lambda: wd(*(int(a) for a in args)),
     "closest": lambda: closest(*args),
     "batch": lambda: batch(*args)}[what]()
