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
from typing import Any, Dict, List, Optional, Tuple, Union

import numpy as np

from . import _millplan
from ._millplan import Mesh, MillplanError, Program, ToolLibrary

__all__ = [
    "MillplanError",
    "Program",
    "Mesh",
    "ToolLibrary",
    "Outcome",
    "inspect",
    "read_program",
    "write_program",
    "read_stl",
    "working_diameter",
    "optimise",
    "dialect_extension",
    "speed",
    "gouge",
    "simulate",
    "force",
    "cut",
    "raster",
    "reorder",
    "feed",
    "setup",
    "post",
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
    library: Union[ToolLibrary, StrPath, None] = None,
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
    post'; a pass named here whose input is missing raises, as the
    command's --passes exits 2), limits (dict of fxy, torque, power, stress, deflection) as in
    the command. dialect: of the output (default as ``write_program``).
    output: a file to write the program to unless a check refuses it.
    library: a tool library (:class:`ToolLibrary` or its file, as the
    command's ``--tools``): each tool the program calls takes the library's
    geometry, flutes, helix and holder; a tool it lacks, has locked or has
    worn out raises MillplanError at the tool call's line.

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
        library,
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


def _table(columns: Dict[str, np.ndarray], pandas: Optional[bool]) -> Any:
    """Columns as a pandas DataFrame when pandas is installed (or asked for
    with ``pandas=True``), else the dict of arrays."""
    if pandas is False:
        return columns
    try:
        import pandas as pd
    except ImportError:
        if pandas:
            raise
        return columns
    return pd.DataFrame(columns)


def speed(
    program: Union[Program, StrPath],
    part: Union[Mesh, StrPath],
    vc: float,
    fz: float,
    flutes: int,
    ap: float,
    machine: Optional[StrPath] = None,
    *,
    ball_d: Optional[float] = None,
    keep_feed: bool = False,
    s_threshold: Optional[float] = None,
    convention: Optional[str] = None,
    normals: Optional[str] = None,
    pandas: Optional[bool] = None,
) -> "Tuple[Program, Any, Dict[str, Any]]":
    """Constant-cutting-speed spindle control: ``millplan speed``.

    For every cutting point of every ball-end operation of ``program`` (a
    Program or a file) the contact with ``part`` (a Mesh or an STL file) is
    found, the working diameter D_w computed and the spindle speed set to
    n = 1000·vc/(π·D_w) within the machine's range and acceleration; the feed
    follows, F = n·flutes·fz, unless ``keep_feed``. Only speeds and feeds
    change, never positions.

    vc: cutting speed, m/min. fz: feed per tooth, mm. flutes: number of
    flutes. ap: stock thickness along the surface normal, mm (at most D/2).
    machine: a machine file (default: the built-in machine). ball_d: ball
    diameter for operations whose tool has no geometry. s_threshold: write a
    new S only when it changes by more than this, 1/min (default as the
    command). convention: which tool point the CL points are, 'auto',
    'tip' or 'centre'. normals: 'smooth', 'facet' or 'ball'.

    Returns ``(new_program, table, report)``. ``table`` has one row per
    cutting point with the columns of the command's ``--table`` CSV (line;
    CL point x, y, z; contact cx, cy, cz; normal nx, ny, nz;
    inclination_deg, feed_angle_deg, uncut_side, ae (NaN: no neighbouring
    pass), d_w, n, feed, n_target, gap, clamped, rate_limited, held,
    gap_flag, corner) and operation, move and the ball diameter d: a pandas
    DataFrame when pandas is installed (``pandas=False``: always the dict
    of NumPy arrays). ``report`` is what ``millplan speed --json`` prints
    (the summary, the checks, the findings, the times before and after)
    without the output file's name and dialect. Runs with the GIL released.
    """
    prog, cols, report = _millplan.speed(
        program, part, vc, fz, ap, flutes, machine, ball_d, keep_feed,
        s_threshold, convention, normals,
    )
    cols["uncut_side"] = np.asarray(_millplan.SIDES)[cols["uncut_side"]]
    report.pop("output", None)
    report.pop("dialect", None)
    return prog, _table(cols, pandas), report


def gouge(
    program: Union[Program, StrPath],
    part: Union[Mesh, StrPath],
    tol: Optional[float] = None,
    step: Optional[float] = None,
    *,
    rapids: bool = False,
    tools: Optional[str] = None,
) -> Dict[str, Any]:
    """Gouge check: ``millplan gouge``.

    Drops each operation's cutter onto ``part`` (a Mesh or an STL file)
    every ``step`` mm (default 0.1) along every cutting move of ``program``
    (and the rapids with ``rapids=True``); a tool tip more than ``tol`` mm
    (default 0.005) below the drop height is a gouge. ``tools``: the cutter
    of operations that name none ('ball:10', 'flat:8', 'bull:10:2',
    'cone:D:ANGLE').

    Returns what ``millplan gouge --json`` prints: moves and points checked,
    the moves skipped by reason, each gouge (operation, move, line, tip
    position ``at``, depth), the deepest, ``clean`` and ``tol``. Raises
    MillplanError when no move could be checked. Runs with the GIL released.
    """
    return _millplan.gouge(program, part, tol, step, rapids, tools)


def simulate(
    program: Union[Program, StrPath],
    stock: str,
    part: Union[Mesh, StrPath, None] = None,
    machine: Optional[StrPath] = None,
    tools: Optional[str] = None,
    *,
    holder: Optional[str] = None,
    flute_length: Optional[float] = None,
    shank: Optional[float] = None,
    resolution: Optional[float] = None,
    tol: Optional[float] = None,
    mesh_resolution: Optional[float] = None,
    output: Optional[StrPath] = None,
    pandas: Optional[bool] = None,
) -> "Tuple[Any, Dict[str, Any]]":
    """Stock simulation: ``millplan simulate``.

    Cuts ``stock`` ('box:auto', 'box:X0,Y0,Z0,X1,Y1,Z1', 'cylinder:auto',
    'stl:FILE', 'offset:MM' around ``part``) with every move of
    ``program`` on a dexel grid of ``resolution`` mm (default 0.1). tools:
    the cutter of operations that name none. holder: 'DIAMETER:STICKOUT',
    mm; flute_length and shank (diameter), mm: the tool body above the
    flutes, for the collision check. tol: material deeper than this (mm,
    default 0.01) met by a rapid or the shank/holder is a collision.
    machine: its rapid rate times the rapids. output: write the stock left
    as a binary STL (at ``mesh_resolution`` mm).

    Returns ``(moves, report)``. ``moves`` has one row per simulated move,
    the columns of the command's ``--table`` CSV: index (over the program),
    line, removed_mm3, mrr (mm³/min), ap and ae (the engagement, mm), air,
    rapid, holder_depth, depth, minutes; a DataFrame when pandas is
    installed (``pandas=False``: the dict of arrays). ``report`` is what
    ``millplan simulate --json`` prints (volumes, collisions, and with a
    part the material left on it). Runs with the GIL released.
    """
    cols, report = _millplan.simulate(
        program, stock, part, machine, tools, holder, flute_length, shank,
        resolution, tol, mesh_resolution, output,
    )
    return _table(cols, pandas), report


def force(
    program: Union[Program, StrPath],
    stock: str,
    material: str,
    part: Union[Mesh, StrPath, None] = None,
    machine: Optional[StrPath] = None,
    tools: Optional[str] = None,
    *,
    flutes: Optional[int] = None,
    resolution: Optional[float] = None,
    pandas: Optional[bool] = None,
) -> "Tuple[Any, Dict[str, Any]]":
    """Cutting forces along a program: ``millplan force PATH``.

    The program runs stroke by stroke through ``stock`` (as in
    :func:`simulate`; 'offset:MM' needs ``part``) on a dexel grid of
    ``resolution`` mm (default 0.1); every cutting stroke's engagement gives
    the forces, torque, power, bending stress and tip deflection over a
    revolution with the coefficients of ``material`` (a name of ``millplan
    force materials``); per move the largest of its strokes. Cutting data
    from the program: spindle speed, feed, fz = feed/(n·flutes) (flutes
    default 2). tools: the cutter of operations that name none.

    Returns ``(moves, summary)``. ``moves`` has one row per simulated move
    with the columns of ``millplan force --table`` (index, line, t_s,
    seconds, rapid, air, unmodelled, rpm, feed, fz, lead_deg, cells, dz_mm,
    dphi_deg, removed_mm3, fxy_max, fx_min … fz_max (N, tool frame),
    torque_max, torque_mean (N·mm), power_w, stress_mpa, deflection_mm,
    fz_allowed): a DataFrame when pandas is installed. ``summary`` has the
    counts and the largest loads (``max``: fxy, torque, power, stress,
    deflection) as ``millplan force --json`` gives them. Runs with the GIL
    released.
    """
    cols, summary = _millplan.force(
        program, stock, material, part, machine, tools, flutes, resolution
    )
    return _table(cols, pandas), summary


def cut(
    tool: str,
    fz: float,
    ap: float,
    n: float,
    ae: Optional[float] = None,
    material: Optional[str] = None,
    *,
    coeffs: Optional[str] = None,
    flutes: Optional[int] = None,
    helix: Optional[float] = None,
    lead: Optional[float] = None,
    tilt: Optional[float] = None,
    variant: Optional[str] = None,
    stickout: Optional[float] = None,
    flute_length: Optional[float] = None,
    modulus: Optional[float] = None,
    dz: Optional[float] = None,
    dphi: Optional[float] = None,
    fixed_grid: bool = False,
    pandas: Optional[bool] = None,
) -> "Tuple[Dict[str, Any], Any]":
    """Forces of one engagement: ``millplan cut``.

    tool: 'ball:D', 'flat:D' or 'bull:D:R' (mm). fz: feed per tooth, mm.
    ap: axial depth, mm. n: spindle speed, 1/min. ae: stepover to the
    earlier pass, mm; None for a full slot. material: a name of ``millplan
    force materials``, or coeffs 'KTC,KRC,KAC,KTE,KRE,KAE'. flutes (default
    4), helix (degrees, default 30), lead and tilt (degrees, default 0) and
    their variant ('tilt-then-lead', the default, or 'lead-then-tilt'),
    stickout (mm, default 3·D), flute_length, modulus (N/mm², default
    carbide), dz (mm) and dphi (degrees): the integration steps, refined
    until F_xy,max and T_max converge unless ``fixed_grid``.

    Returns ``(figures, curves)``: ``figures`` is what ``millplan cut
    --json`` prints (force ranges in the tool and workpiece frame, F_xy,max,
    torque, power, bending stress, deflection, the steps used);
    ``curves`` the forces over one revolution as the command's ``--csv``
    (phi_deg, fx, fy, fz, fx_w, fy_w, fz_w, torque): a DataFrame when
    pandas is installed.
    """
    figures, curves = _millplan.cut(
        tool, fz, ap, n, ae, material, coeffs, flutes, helix, lead, tilt,
        variant, stickout, flute_length, modulus, dz, dphi, fixed_grid,
    )
    return figures, _table(curves, pandas)


def raster(
    part: Union[Mesh, StrPath],
    tool: str,
    stepover: float,
    step: float,
    *,
    angle: Optional[float] = None,
    oneway: bool = False,
    boundary: Optional[float] = None,
    tol: Optional[float] = None,
    clearance: Optional[float] = None,
    feed: Optional[float] = None,
    spindle: Optional[float] = None,
    machine: Optional[StrPath] = None,
    dialect: Optional[str] = None,
    force: bool = False,
) -> "Tuple[Program, Dict[str, Any]]":
    """Raster finishing path by drop-cutter: ``millplan raster``.

    Drops ``tool`` ('ball:D', 'flat:D', 'bull:D:R') onto ``part`` (a Mesh or
    an STL file) along parallel lines ``stepover`` mm apart (at ``angle``
    degrees from X, default 0), every ``step`` mm along them, zigzag unless
    ``oneway``; ``boundary`` mm inside the part's XY box (negative:
    outside); points added where the path would leave the surface by more
    than ``tol`` mm (default 0.002; 0: none); rapids ``clearance`` mm above
    the part (default 5); ``feed`` mm/min (default 1500), ``spindle`` 1/min
    (default 6000).

    The program is written in ``dialect`` (default the machine's, else
    apt), read back and checked (read-back, machine limits, gouges) as the
    command does; a failed check raises MillplanError unless ``force``.
    Returns ``(program, report)``, the report as ``millplan raster --json``
    prints it without the output's name. Write the program with
    :func:`write_program`. Runs with the GIL released.
    """
    prog, report = _millplan.raster(
        part, tool, stepover, step, angle, oneway, boundary, tol, clearance,
        feed, spindle, machine, dialect, force,
    )
    report.pop("output", None)
    return prog, report


def reorder(
    program: Union[Program, StrPath],
    part: Union[Mesh, StrPath],
    method: Optional[str] = None,
    *,
    start: Optional[str] = None,
    start_index: Optional[int] = None,
    seed: Optional[int] = None,
    n_min: Optional[int] = None,
    tie: Optional[float] = None,
    max_step: Optional[float] = None,
    vc: Optional[float] = None,
    fz: Optional[float] = None,
    flutes: Optional[int] = None,
    ap: Optional[float] = None,
    speed: bool = True,
    machine: Optional[StrPath] = None,
) -> "Tuple[Program, Dict[str, Any]]":
    """Reorder finishing points so the working diameter changes least
    between successive points, with safe links: ``millplan reorder``.

    method: 'as-run' (default: the order that runs best, the original kept
    when none is better), 'paper' or 'optimised'. start: 'lowest'
    (default), 'highest' or 'random' (with ``seed``), or ``start_index``.
    n_min, tie (mm), max_step (mm; 0: no limit) tune the search as the
    command's options do. Unless ``speed=False`` the constant-cutting-speed
    pass runs after it with vc (m/min), fz (mm), flutes and ap (mm)
    (defaults 63, 0.125, 2, 0.3). ``part``: a Mesh or an STL file.

    Returns ``(program, summary)``, the summary as ``millplan reorder
    --json`` prints it (both orders' indicators, the verdict, the checks)
    without the output's name. Runs with the GIL released.
    """
    prog, summary = _millplan.reorder(
        program, part, method, start, start_index, seed, n_min, tie, max_step,
        vc, fz, flutes, ap, speed, machine,
    )
    summary.pop("output", None)
    return prog, summary


def feed(
    program: Union[Program, StrPath],
    stock: str,
    material: str,
    part: Union[Mesh, StrPath, None] = None,
    machine: Optional[StrPath] = None,
    tools: Optional[str] = None,
    *,
    flutes: Optional[int] = None,
    helix: Optional[float] = None,
    stickout: Optional[float] = None,
    flute_length: Optional[float] = None,
    modulus: Optional[float] = None,
    resolution: Optional[float] = None,
    dz: Optional[float] = None,
    dphi: Optional[float] = None,
    fixed_grid: bool = False,
    spindle: Optional[float] = None,
    fz_min: Optional[float] = None,
    fz_max: Optional[float] = None,
    fos: Optional[float] = None,
    feed_accel: Optional[float] = None,
    limits: Optional[Dict[str, float]] = None,
    dialect: Optional[str] = None,
    output: Optional[StrPath] = None,
    pandas: Optional[bool] = None,
) -> "Tuple[Program, str, Dict[str, Any], Any]":
    """A feed per block from the cutting forces: ``millplan feed``.

    The program runs stroke by stroke through ``stock`` (as in
    :func:`force`; 'offset:MM' needs ``part``) on a dexel grid of
    ``resolution`` mm (default 0.1) with the coefficients of ``material``;
    each cutting block gets the feed per tooth at which the tightest limit
    is met: ``limits`` (dict of fxy N, torque N·mm, power W, stress MPa,
    deflection mm, and fz_min/fz_max mm) and the machine file's spindle
    chart, power, torque and stress divided by ``fos`` (default 1). Blocks
    in air run at the machine's air feed, else at the tool's largest feed
    per tooth. Feeds stay within ``fz_min`` (default 0.01 mm) ..
    ``fz_max`` (default per tool: the material's chip load at its
    diameter) and the machine's feed range; changes between blocks stay
    within ``feed_accel`` (mm/s², default the machine's smallest
    linear-axis acceleration) by lowering feeds only. Positions, spindle
    speeds and feed modes are kept.

    The model: flutes (default 2), helix (degrees, default 30), stickout
    (mm, default 3·D), flute_length (mm), modulus (N/mm², default carbide),
    dz (mm) and dphi (degrees) the force model's coarsest steps, refined per
    load sample until F_xy,max and T_max converge unless ``fixed_grid``;
    spindle (1/min) for moves without an S word.
    tools: the cutter of operations that name none ('ball:10', 'flat:8',
    'bull:10:2').

    Returns ``(program, text, summary, moves)``: the program with the new
    feeds, its text in ``dialect`` (default the machine's, else the file
    name's, else the input's; written to ``output`` when given), what
    ``millplan feed --json`` prints (times before and after, the largest
    loads before and after, the binding limits, moves still over a limit),
    and per move of the input its loads with the feed allowed
    (``fz_allowed``; the columns of :func:`force`): a DataFrame when pandas
    is installed. Runs with the GIL released.
    """
    prog, text, summary, moves = _millplan.feed(
        program, stock, material, part, machine, tools, flutes, helix,
        stickout, flute_length, modulus, resolution, dz, dphi, fixed_grid,
        spindle, fz_min, fz_max, fos, feed_accel, limits, dialect, output,
    )
    return prog, text, summary, _table(moves, pandas)


def setup(
    part: Union[Mesh, StrPath],
    machine: Optional[StrPath] = None,
    kind: Optional[str] = None,
    range1: Optional[str] = None,
    range2: Optional[str] = None,
    *,
    grid: Optional[str] = None,
    cells: Optional[int] = None,
    tool: Optional[str] = None,
    clearance: Optional[float] = None,
    ignore_bottom: bool = False,
    exact: bool = False,
) -> "Tuple[Dict[str, Any], Mesh]":
    """Can a five-axis machine reach the whole part in one setup, and how
    should it be clamped: ``millplan setup``.

    The machine: a machine file with a ``[kinematics]`` table, or ``kind``
    'ca' (a tilting A table carrying a C table; range1 the A axis, range2
    the C table) or 'ab' (an A table on a B cradle), each range 'MIN,MAX'
    in degrees or 'free' (the default). Every facet of ``part`` (a Mesh or
    an STL file) gets the grid directions that leave it by more than
    ``clearance`` degrees (default 0) and see no other part of the part
    (with ``tool`` 'D,REACH[,HOLDER_D,HOLDER_LENGTH]' in mm: along which a
    ball-end mill, its shank and holder touch nothing but the facet); the
    search finds the setup needing the least of the rotary ranges. grid:
    'latlon' (default), 'icosphere' or 'healpix', about ``cells`` cells
    (default 1200). ignore_bottom: the part stands on its bottom face.
    exact: the exact window algorithm for a C axis (slow on fine grids).

    Returns ``(report, rotated)``: what ``millplan setup --json`` prints
    (feasible, the setup rotation, the ranges required, the facets out of
    reach) and the part turned into the setup found (what ``-o`` writes).
    Runs with the GIL released.
    """
    return _millplan.setup(
        part, machine, kind, range1, range2, grid, cells, tool, clearance,
        ignore_bottom, exact,
    )


def post(
    program: Union[Program, StrPath],
    machine: StrPath,
    output: Optional[StrPath] = None,
    dialect: Optional[str] = None,
    *,
    tcp: bool = False,
    g93: bool = False,
    tol: Optional[float] = None,
    pole_cone: Optional[float] = None,
    pole_tol: Optional[float] = None,
    clearance: Optional[float] = None,
    force: bool = False,
) -> "Tuple[Program, str, Dict[str, Any]]":
    """Post a five-axis CL program for a machine: ``millplan post``.

    The rotary angles come from ``machine``'s kinematics (a machine file
    with a ``[kinematics]`` table), chosen over the whole path: the path of
    least rotary travel that never changes branch inside a cut (a change
    across a rapid gets a retract of ``clearance`` mm along the tool axis).
    Within ``pole_cone`` degrees of the pole the turning axis is held, and
    blocks deviating more than ``pole_tol`` degrees are flagged (defaults:
    the machine file's ``[post]``, else 1, 1 and 50). Without ``tcp`` the
    program is in machine coordinates and points are inserted wherever the
    tip would leave the CL segment by more than ``tol`` mm (default 0.01);
    with ``tcp`` tool tips under the control's TCP mode. ``g93``: inverse
    time feed. dialect: default the machine's control, else ``output``'s
    extension; G-code only.

    The written program is read back and checked (the IR, S and F within
    the machine, every posted tip on the CL path within ``tol``); a check
    that fails raises MillplanError at the CL line unless ``force``.
    Returns ``(program, text, summary)``: the posted program, its text
    (written to ``output`` when given) and what ``millplan post --json``
    prints. Runs with the GIL released.
    """
    return _millplan.post(
        program, machine, output, dialect, tcp, g93, tol, pole_cone, pole_tol,
        clearance, force,
    )
