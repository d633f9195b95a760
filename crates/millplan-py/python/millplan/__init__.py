"""millplan from Python: NC programs, parts, process models and the
optimising job of ``millplan optimise``, with NumPy arrays in and out.

Everything is computed by millplan's Rust library crates; the long
computations release the GIL, so threads and Dask workers run in parallel.
Bad input raises :class:`MillplanError` (a ``ValueError``) carrying the
``file``, ``line`` and ``col`` where the input is wrong.

Units: lengths in mm, feeds in mm/min, spindle speeds in 1/min, angles in
degrees, times in seconds, forces in N.

>>> import millplan
>>> round(float(millplan.working_diameter(10, 0.3, 0.25, 20, 45, "left")), 4)
4.1301
"""

from __future__ import annotations

from dataclasses import dataclass, field
from os import PathLike
from typing import Any, Dict, List, Optional, Union

import numpy as np

from . import _millplan
from ._millplan import Mesh, MillplanError, Program

__all__ = [
    "MillplanError",
    "Program",
    "Mesh",
    "Outcome",
    "inspect",
    "read_program",
    "write_program",
    "read_stl",
    "working_diameter",
    "optimise",
    "dialect_extension",
]

StrPath = Union[str, "PathLike[str]"]


def inspect(
    path: StrPath, machine: Optional[StrPath] = None, units: Optional[str] = None
) -> Dict[str, Any]:
    """What a file holds, with the keys of ``millplan inspect --json``.

    For a program (APT/CL or G-code, detected from the content): format,
    dialect, units, operations, tools, move counts, bounds, path lengths and
    the time estimate with acceleration on ``machine`` (a machine file;
    default: the built-in three-axis machine). For an STL: triangles,
    defects, bounds and the unit its size suggests. ``units`` ("mm" or
    "inch") overrides the source's unit.
    """
    return _millplan.inspect(path, machine, units)


def read_program(path: StrPath, units: Optional[str] = None) -> Program:
    """Read an APT/CL or G-code program into millplan's IR.

    The moves are arrays on the result: ``xyz`` and ``axis`` (n, 3),
    ``feed``, ``spindle``, ``kind``, ``line``, ``operation`` (n,).
    """
    return _millplan.read_program(path, units)


def write_program(
    program: Program,
    path: StrPath,
    dialect: Optional[str] = None,
    machine: Optional[StrPath] = None,
) -> str:
    """Write ``program`` to ``path`` and return the dialect written.

    ``dialect``: fanuc, sinumerik, heidenhain, linuxcnc or apt; default the
    one the file name's extension names, else the program's source dialect.
    A machine file adds its control's settings (spindle decimals, G93 words).
    """
    return _millplan.write_program(program, path, dialect, machine)


def dialect_extension(dialect: str) -> str:
    """The usual file extension of a dialect's programs: fanuc → nc,
    sinumerik → mpf, heidenhain → h, linuxcnc → ngc, apt → apt."""
    return _millplan.dialect_extension(dialect)


def read_stl(path: StrPath, units: Optional[str] = None) -> Mesh:
    """Read an STL part (binary or ASCII); ``units="inch"`` scales it to mm."""
    return _millplan.read_stl(path, units)


def _side_is_right(side: Any) -> np.ndarray:
    s = np.asarray(side)
    if s.dtype == bool:
        return s
    if s.dtype.kind not in "US":
        raise MillplanError("side: must be 'left' or 'right'")
    bad = ~np.isin(s, ["left", "right"])
    if bad.any():
        raise MillplanError(
            f"side: {s[bad].ravel()[0]!r}: must be 'left' or 'right'"
        )
    return s == "right"


def working_diameter(
    d: Any,
    ap: Any,
    ae: Any,
    alpha: Any,
    af: Any,
    side: Any = "left",
    *,
    both: bool = False,
) -> Any:
    """Working diameter D_w of a ball-end mill, mm (the paper's model).

    The tool diameter at the highest engaged point of the ball on a locally
    planar surface. Every argument broadcasts as in NumPy; a scalar result
    for scalar arguments, else an array of the broadcast shape.

    d: ball diameter, mm. ap: stock thickness along the surface normal, mm
    (0 < ap <= d/2). ae: distance to the machined neighbouring pass, mm;
    ``None`` (or ``inf`` elementwise) for none (a first or isolated pass).
    alpha: surface inclination, degrees (0 <= alpha < 90). af: feed direction
    relative to uphill, degrees (0 uphill, 180 downhill). side: 'left' or
    'right', the side of the feed the uncut material is on (with M3, right
    is climb milling); an array of them, or booleans (True: right).
    both: the neighbouring passes on both sides are machined.

    Computed in Rust over the whole arrays with the GIL released. An
    element outside the model's domain raises MillplanError naming it.
    """
    right = _side_is_right(side)
    args = [np.asarray(x, dtype=np.float64) for x in (d, ap, alpha, af)]
    ae_a = None if ae is None else np.asarray(ae, dtype=np.float64)
    shapes = [a.shape for a in args] + [right.shape]
    if ae_a is not None:
        shapes.append(ae_a.shape)
    shape = np.broadcast_shapes(*shapes)

    def flat(a: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(np.broadcast_to(a, shape)).reshape(-1)

    dd, aa, al, ff = (flat(a) for a in args)
    out = _millplan._working_diameter(
        dd,
        aa,
        None if ae_a is None else flat(ae_a),
        al,
        ff,
        flat(right),
        both,
    ).reshape(shape)
    return float(out) if shape == () else out


@dataclass
class Outcome:
    """What ``optimise`` concluded, as ``millplan optimise --json`` says it.

    verdict: 'improved', 'kept' or 'refused'. time_before_s / time_after_s:
    the cycle time estimated with acceleration. max_before / max_after: the
    largest loads (fxy N, torque N·mm, power W, deflection mm) where a stock
    and material were given, else None. checks: each check of the written
    program (name, ok, checked, unit, skipped, findings). passes: each pass
    (name, ran, reason, seconds). text: the written program. written: the
    file written, if any.
    """

    verdict: str
    time_before_s: float
    time_after_s: float
    max_before: Optional[Dict[str, float]]
    max_after: Optional[Dict[str, float]]
    checks: List[Dict[str, Any]]
    passes: List[Dict[str, Any]]
    dialect: str
    text: str = field(repr=False)
    summary: Dict[str, Any] = field(repr=False)
    written: Optional[str] = None

    @property
    def refused(self) -> bool:
        """A check failed: the program was not written."""
        return self.verdict == "refused"

    @property
    def failed_checks(self) -> List[str]:
        """Names of the checks that failed."""
        return [c["name"] for c in self.checks if not c["ok"]]


def optimise(
    program: Union[Program, StrPath],
    part: Union[Mesh, StrPath, None] = None,
    stock: Optional[str] = None,
    machine: Optional[StrPath] = None,
    material: Optional[str] = None,
    tools: Optional[str] = None,
    *,
    flutes: Optional[int] = None,
    vc: Optional[float] = None,
    resolution: Optional[float] = None,
    passes: Optional[str] = None,
    limits: Optional[Dict[str, float]] = None,
    dialect: Optional[str] = None,
    output: Optional[StrPath] = None,
) -> "tuple[Program, Outcome]":
    """Take a CAM program to a verified, better program: ``millplan optimise``.

    program: a Program or a file. part: the part surface (Mesh or STL file)
    for speed and reorder. stock: 'box:auto', 'box:X0,Y0,Z0,X1,Y1,Z1',
    'cylinder:auto', 'stl:FILE' or 'offset:MM', for the feed pass and the
    load checks (with ``material``, a name of ``millplan force materials``).
    machine: a machine file (default: the built-in machine). tools: cutter
    of operations without one, or overriding it ('ball:10', 'flat:8',
    'bull:10:2'). flutes, vc (m/min), resolution (the stock's dexel size, mm; default
    0.1), passes ('speed,reorder,orient,feed,
    post'), limits (dict of fxy, torque, power, stress, deflection) as in
    the command. dialect: of the output (default as ``write_program``).
    output: a file to write the program to unless a check refuses it.

    Returns the written program (read back from its own text) and the
    :class:`Outcome`. Runs with the GIL released.
    """
    prog, text, summary, refused = _millplan.optimise(
        program,
        part,
        stock,
        machine,
        material,
        tools,
        flutes,
        vc,
        resolution,
        passes,
        limits,
        dialect,
        output,
    )
    outcome = Outcome(
        verdict=summary["verdict"],
        time_before_s=summary["time_before_s"],
        time_after_s=summary["time_after_s"],
        max_before=summary.get("max_before"),
        max_after=summary.get("max_after"),
        checks=summary["checks"],
        passes=summary["passes"],
        dialect=summary["dialect"],
        text=text,
        summary=summary,
        written=None if (output is None or refused) else str(output),
    )
    return prog, outcome
