#!/usr/bin/env python3
"""Optimise every program in a folder with Dask and print the summary table.

    python examples/python/batch.py cam/ --stl part.stl --stock offset:0.5 \
        --machine machine.toml --material al7075 --output optimised/ --csv summary.csv

Without --scheduler a LocalCluster on this machine runs one task per
program; with --scheduler tcp://HOST:8786 the programs run on that cluster
(its workers need millplan installed and the files at the same paths).
Exit code 0 when every program was optimised and written, 1 when one was
refused by a check or could not be read (its row says why).
"""

import argparse
import sys

from millplan.batch import optimise_folder


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("folder", help="folder of programs (APT/CL or G-code)")
    ap.add_argument("--scheduler", help="address of a Dask scheduler (default: a LocalCluster)")
    ap.add_argument("--workers", type=int, help="LocalCluster worker processes (default: one per core)")
    ap.add_argument("--threads", type=int, default=1, help="threads per LocalCluster worker (default 1)")
    ap.add_argument("--stl", help="part surface, for the speed and reorder passes")
    ap.add_argument("--stock", help="initial stock, e.g. box:auto or offset:0.5, for the feed pass")
    ap.add_argument("--machine", help="machine file (default: the built-in machine)")
    ap.add_argument("--material", help="material name, e.g. al7075")
    ap.add_argument("--tool", help="cutter of operations without one, e.g. ball:10")
    ap.add_argument("--passes", help="passes to run, comma-separated (default: all the inputs allow)")
    ap.add_argument("--output", help="folder for the optimised programs (default: none written)")
    ap.add_argument("--csv", help="also write the summary table to this CSV file")
    a = ap.parse_args()
    df = optimise_folder(
        a.folder,
        client=a.scheduler,
        workers=a.workers,
        threads_per_worker=a.threads,
        csv=a.csv,
        part=a.stl,
        stock=a.stock,
        machine=a.machine,
        material=a.material,
        tools=a.tool,
        passes=a.passes,
        output=a.output,
    )
    with __import__("pandas").option_context("display.width", 200, "display.max_columns", 20):
        print(df.drop(columns=["checks"]).to_string(index=False))
    return 0 if (df["verdict"].isin(["improved", "kept"])).all() else 1


if __name__ == "__main__":
    sys.exit(main())
