"""Optimise every program in a folder on a Dask cluster.

One Dask task per program runs :func:`millplan.optimise` (its Rust work
releases the GIL); the results are gathered into one summary table, a
pandas DataFrame and, if asked, a CSV file, one row per program:

``file, verdict, time_before_s, time_after_s, fxy_before_n, fxy_after_n,
checks, failed_checks, error``

A program that cannot be read or optimised gets the verdict ``error`` and
its message (with file, line and column) in ``error``; the batch goes on.

By default a ``dask.distributed.LocalCluster`` on this machine runs the
tasks; give ``client`` a scheduler address (``"tcp://host:8786"``) or a
``dask.distributed.Client`` to run them on a cluster. The workers need
millplan installed and the files at the same paths (a shared folder).

>>> from millplan.batch import optimise_folder
>>> table = optimise_folder("cam/", stock="box:auto", material="al7075",
...                         machine="machine.toml", output="optimised/")
"""

from __future__ import annotations

import glob
import os
from typing import Any, Dict, List, Optional, Union

#: The columns of the summary table, in order.
COLUMNS = [
    "file",
    "verdict",
    "time_before_s",
    "time_after_s",
    "fxy_before_n",
    "fxy_after_n",
    "checks",
    "failed_checks",
    "error",
]

#: File name patterns taken as programs by default.
PROGRAMS = ("*.apt", "*.cl", "*.cls", "*.nc", "*.ngc", "*.mpf", "*.h", "*.tap", "*.gcode")


def optimise_one(path: str, options: Dict[str, Any]) -> Dict[str, Any]:
    """Optimise one program; a row of the summary table, never an exception.

    ``options`` are :func:`millplan.optimise`'s keyword arguments; an
    ``output`` folder there receives the optimised program (unless a check
    refused it) under its name with the extension of the dialect written.
    """
    import millplan

    opts = dict(options)
    out_dir = opts.pop("output", None)
    row: Dict[str, Any] = {c: None for c in COLUMNS}
    row["file"] = os.path.basename(path)
    try:
        _, o = millplan.optimise(path, **opts)
        if out_dir is not None and not o.refused:
            stem = os.path.splitext(os.path.basename(path))[0]
            name = f"{stem}.{millplan.dialect_extension(o.dialect)}"
            with open(os.path.join(out_dir, name), "w", newline="") as f:
                f.write(o.text)
    except Exception as e:  # one file's failure is one row, not the batch's
        row["verdict"] = "error"
        row["error"] = f"{type(e).__name__}: {e}"
        return row
    row.update(
        verdict=o.verdict,
        time_before_s=o.time_before_s,
        time_after_s=o.time_after_s,
        fxy_before_n=(o.max_before or {}).get("fxy"),
        fxy_after_n=(o.max_after or {}).get("fxy"),
        checks=" ".join(f"{c['name']}:{'ok' if c['ok'] else 'FAILED'}" for c in o.checks),
        failed_checks=" ".join(o.failed_checks),
    )
    return row


def programs_in(folder: str, patterns: Union[str, List[str], tuple] = PROGRAMS) -> List[str]:
    """The program files of ``folder`` matching ``patterns``, sorted."""
    if isinstance(patterns, str):
        patterns = [patterns]
    found = set()
    for p in patterns:
        found.update(glob.glob(os.path.join(folder, p)))
    return sorted(f for f in found if os.path.isfile(f))


def table(rows: List[Dict[str, Any]]):
    """Rows as a pandas DataFrame with the columns of :data:`COLUMNS`."""
    import pandas as pd

    return pd.DataFrame(rows, columns=COLUMNS)


def optimise_folder(
    folder: str,
    *,
    client: Any = None,
    patterns: Union[str, List[str], tuple] = PROGRAMS,
    csv: Optional[str] = None,
    workers: Optional[int] = None,
    threads_per_worker: int = 1,
    **options: Any,
):
    """Optimise every program in ``folder`` with Dask, one task per program.

    client: None (a LocalCluster of ``workers`` processes with
    ``threads_per_worker`` threads each, closed afterwards), a scheduler
    address, or a ``dask.distributed.Client``. patterns: file name
    patterns of programs. csv: also write the table there. options:
    :func:`millplan.optimise`'s keyword arguments (part, stock, machine,
    material, tools, flutes, vc, passes, limits, dialect), and ``output``, a
    folder for the optimised programs.

    Returns the summary table as a pandas DataFrame, rows in file order.
    """
    from dask.distributed import Client, LocalCluster

    files = programs_in(folder, patterns)
    if options.get("output") is not None:
        os.makedirs(options["output"], exist_ok=True)
    own, cluster = None, None
    if client is None:
        cluster = LocalCluster(
            n_workers=workers, threads_per_worker=threads_per_worker, processes=True
        )
        own = client = Client(cluster)
    elif isinstance(client, str):
        own = client = Client(client)
    try:
        futures = client.map(optimise_one, files, options=options, pure=False)
        rows = client.gather(futures)
    finally:
        if own is not None:
            own.close()
        if cluster is not None:
            cluster.close()
    df = table(rows)
    if csv is not None:
        df.to_csv(csv, index=False)
    return df
