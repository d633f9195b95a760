#!/usr/bin/env python3
"""Benchmarks of the Python package against the Rust it wraps.

    python bench.py wd [N]                        # working_diameter over N (1,000,000) cases
    python bench.py closest STL APT [R]           # closest points of the ball centres of APT's cutting moves
    python bench.py batch FOLDER PART MACHINE     # Dask batch on 2 workers x 1 thread vs one process
    python bench.py raster PART OUT.apt [N]       # a ball-end raster of about N (1,000,000) points on PART, by drop-cutter
    python bench.py gil [N]                       # a Python loop's pace beside working_diameter (GIL released?), CPU time of a call

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
    """working_diameter over the N cases of millplan-bench's wd_rate example."""
    ae, alpha, af, side = wd_cases(n)
    t, v = best_of(5, lambda: millplan.working_diameter(10.0, 0.3, ae, alpha, af, side))
    print(f"{n} cases: {t:.4f} s ({n / t / 1e6:.2f} M/s, sum {v.sum():.6f}), "
          f"RAYON_NUM_THREADS={os.environ.get('RAYON_NUM_THREADS', 'all')}, load {os.getloadavg()[0]:.1f}")
    return t, float(v.sum())


def wd_cases(n):
    """The cases of millplan-bench's wd_rate example, by the same formulas."""
    i = np.arange(n, dtype=np.float64)
    ae = 0.25 + (i * 0.569840290998053) % 1.0
    ae[::10] = np.inf
    alpha = 80.0 * ((i * 0.618033988749895) % 1.0)
    af = -180.0 + 360.0 * ((i * 0.754877666246693) % 1.0)
    side = np.where(np.arange(n) % 2 == 0, "left", "right")
    return ae, alpha, af, side


def gil(n=1_000_000):
    """Whether the GIL is free while Rust runs: a pure-Python loop counts on
    the main thread, alone and then while another thread runs
    working_diameter over N cases. Held, the loop would stand still during
    the call (ratio near 0); released, it counts at its own pace (ratio
    near 1, whatever the machine's load, since both threads are starved
    alike). Also the CPU time of one call (a loaded machine's wall time
    says little). Run with RAYON_NUM_THREADS=1."""
    import threading

    ae, alpha, af, side = wd_cases(n)

    def work():
        millplan.working_diameter(10.0, 0.3, ae, alpha, af, side)

    def spin(until):
        k = 0
        while not until():
            k += 1
        return k

    work()
    c0, w0 = time.process_time(), time.perf_counter()
    work()
    cpu, wall = time.process_time() - c0, time.perf_counter() - w0
    t0 = time.perf_counter()
    alone = spin(lambda: time.perf_counter() - t0 > wall) / (time.perf_counter() - t0)
    t = threading.Thread(target=work)
    t0 = time.perf_counter()
    t.start()
    during = spin(lambda: not t.is_alive()) / (time.perf_counter() - t0)
    t.join()
    print(f"one call over {n} cases: {cpu:.3f} s CPU ({n / cpu / 1e6:.2f} M cases per CPU second), "
          f"{wall:.3f} s wall; a Python loop beside it runs at {during / alone:.2f} of its pace alone "
          f"(0: GIL held); RAYON_NUM_THREADS={os.environ.get('RAYON_NUM_THREADS', 'all')}, "
          f"load {os.getloadavg()[0]:.1f}")


def raster(stl, out, n=1_000_000):
    """A zigzag D10 ball-end raster of about N points over the part's XY
    box, each point the tool tip dropped onto the part (Mesh.drop_cutter),
    written as APT: an input for `millplan speed --timings` and `closest`."""
    part = millplan.read_stl(stl)
    lo, hi = part.vertices.min(axis=0), part.vertices.max(axis=0)
    k = int(np.sqrt(n))
    xs, ys = np.linspace(lo[0], hi[0], k), np.linspace(lo[1], hi[1], k)
    x, y = np.meshgrid(xs, ys)
    x[1::2] = x[1::2, ::-1]  # zigzag
    xy = np.stack([x.ravel(), y.ravel()], axis=1)
    z = part.drop_cutter("ball:10", xy)
    keep = np.isfinite(z)
    pts = np.column_stack([xy[keep], z[keep]])
    top = hi[2] + 10.0
    with open(out, "w") as f:
        f.write("PARTNO BENCH_RASTER\nUNITS/MM\nCUTTER/10,5,0,5,0,0,0\nLOADTL/1\n"
                "SPINDL/6000,RPM,CLW\nRAPID\n")
        f.write(f"GOTO/{pts[0, 0]:.6f},{pts[0, 1]:.6f},{top:.6f}\nFEDRAT/1500,MMPM\n")
        np.savetxt(f, pts, fmt="GOTO/%.6f,%.6f,%.6f")
        f.write(f"GOTO/{pts[-1, 0]:.6f},{pts[-1, 1]:.6f},{top:.6f}\nFINI\n")
    print(f"{out}: {len(pts)} cutting points")


def closest(stl, apt, r=5.0):
    part = millplan.read_stl(stl)
    p = millplan.read_program(apt)
    centres = p.xyz[p.kind == 1] + [0.0, 0.0, float(r)]
    t0 = time.perf_counter()
    part.closest_points(centres[:1])  # builds the tree
    build = time.perf_counter() - t0
    c0 = time.process_time()
    t, (_, d, _) = best_of(3, lambda: part.closest_points(centres, 3 * float(r) + 1.3))
    cpu = (time.process_time() - c0) / 3
    print(f"{len(part)} triangles, tree {build:.3f} s; {len(centres)} points {t:.3f} s wall, "
          f"{cpu:.3f} s CPU a call ({t / len(centres) * 1e6:.2f} µs each), "
          f"mean distance {np.nanmean(d[np.isfinite(d)]):.6f}; load {os.getloadavg()[0]:.1f}")
    return t, cpu, len(centres)


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
    # A cluster that is already running (as a shop's is): started, and
    # millplan imported in each worker, before the clock starts.
    from dask.distributed import Client, LocalCluster

    t = time.perf_counter()
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True) as cluster, \
            Client(cluster) as client:
        client.run(lambda: __import__("millplan") and None)
        start = time.perf_counter() - t
        t = time.perf_counter()
        df = optimise_folder(folder, client=client, **opts)
        warm = time.perf_counter() - t
    assert [r["verdict"] for r in rows] == list(df["verdict"]), (rows, df)
    print(f"on a running cluster: warm {warm:.1f} s, {one / warm:.2f}x (its start took {start:.1f} s)")
    return one, two, len(files)


if __name__ == "__main__":
    what, args = sys.argv[1], sys.argv[2:]
    {"wd": lambda: wd(*(int(a) for a in args)),
     "closest": lambda: closest(*args),
     "gil": lambda: gil(*(int(a) for a in args)),
     "raster": lambda: raster(args[0], args[1], *(int(a) for a in args[2:])),
     "batch": lambda: batch(*args)}[what]()
