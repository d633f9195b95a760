"""Type stubs of the extension module (thin wrappers over millplan's crates)."""

from os import PathLike
from typing import Any, Dict, List, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

StrPath = Union[str, PathLike[str]]

class MillplanError(ValueError):
    """Bad input, located: ``file`` (or the argument's name), ``line`` and
    ``col`` (1-based, None where the error has no place), ``message``."""

    file: Optional[str]
    line: Optional[int]
    col: Optional[int]
    message: str

class Program:
    """A program in millplan's IR: mm, mm/min, 1/min."""

    KINDS: Tuple[str, str, str, str]
    @property
    def xyz(self) -> npt.NDArray[np.float64]:
        """Tool-tip end point of each move, (n, 3), NaN where unknown."""
    @property
    def axis(self) -> npt.NDArray[np.float64]:
        """Unit tool axis of each move, (n, 3), NaN for three-axis moves."""
    @property
    def feed(self) -> npt.NDArray[np.float64]:
        """Feed of each move (0 on rapids), (n,)."""
    @property
    def spindle(self) -> npt.NDArray[np.float64]:
        """Spindle speed of each move, 1/min, (n,)."""
    @property
    def kind(self) -> npt.NDArray[np.uint8]:
        """Kind code of each move: index into KINDS, (n,)."""
    @property
    def line(self) -> npt.NDArray[np.uint32]:
        """1-based source line of each move (0: generated), (n,)."""
    @property
    def operation(self) -> npt.NDArray[np.uint32]:
        """Operation index of each move, (n,)."""
    @property
    def operations(self) -> List[Dict[str, Any]]:
        """Name, move count and tool number of each operation."""
    @property
    def tools(self) -> List[Dict[str, Any]]:
        """The tools, as inspect lists them."""
    @property
    def path(self) -> Optional[str]:
        """The file it was read from."""
    @property
    def diagnostics(self) -> List[str]:
        """The reader's notes, 'file:line:col: message'."""
    @property
    def dialect(self) -> str:
        """Source dialect."""
    def ir(self) -> str:
        """The IR as text."""
    def summary(self, machine: Optional[str] = None) -> Dict[str, Any]:
        """The summary inspect gives for this program."""
    def __len__(self) -> int: ...

class Mesh:
    """A triangle mesh (a part), mm."""

    @property
    def vertices(self) -> npt.NDArray[np.float64]:
        """Welded vertex positions, (n, 3)."""
    @property
    def faces(self) -> npt.NDArray[np.uint32]:
        """Triangles as vertex indices, (m, 3)."""
    def closest_points(
        self, points: npt.ArrayLike, max_distance: float = ...
    ) -> Tuple[
        npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.int64]
    ]:
        """Closest surface point, distance and triangle of each point
        (NaN, inf, -1 where none lies within max_distance)."""
    def drop_cutter(
        self, cutter: str, xy: npt.ArrayLike
    ) -> npt.NDArray[np.float64]:
        """Tool-tip height of cutter dropped at each (x, y), NaN: no contact."""
    def __len__(self) -> int: ...

class ToolLibrary:
    """A tool library file (``millplan tool``'s), read when opened; a
    missing file raises MillplanError (it is never taken for an empty one)."""

    def __init__(self, path: StrPath) -> None: ...
    @property
    def tools(self) -> List[Dict[str, Any]]:
        """Every tool, as ``millplan tool show --json`` lists them."""
    @property
    def numbers(self) -> List[int]:
        """The tool numbers, ascending."""
    @property
    def path(self) -> str:
        """The library's file."""
    def cutter(self, number: int) -> Optional[Dict[str, Any]]:
        """The cutter the library gives the tool: d, r (corner radius),
        flute_length (mm); None for a kind millplan cannot shape."""
    def decision(self, number: int) -> Optional[str]:
        """The last decision logged about the tool (worn, broken, ...)."""
    def log(self, number: Optional[int] = None) -> List[Dict[str, Any]]:
        """The decision log, as ``millplan tool log --json``."""
    def __getitem__(self, number: int) -> Dict[str, Any]: ...
    def __contains__(self, number: int) -> bool: ...
    def __len__(self) -> int: ...

def inspect(
    path: StrPath, machine: Optional[StrPath] = None, units: Optional[str] = None
) -> Dict[str, Any]: ...
def read_program(path: StrPath, units: Optional[str] = None) -> Program: ...
def write_program(
    program: Program,
    path: StrPath,
    dialect: Optional[str] = None,
    machine: Optional[StrPath] = None,
) -> str: ...
def read_stl(path: StrPath, units: Optional[str] = None) -> Mesh: ...
def _working_diameter(
    d: npt.NDArray[np.float64],
    ap: npt.NDArray[np.float64],
    ae: Optional[npt.NDArray[np.float64]],
    alpha: npt.NDArray[np.float64],
    af: npt.NDArray[np.float64],
    right: npt.NDArray[np.bool_],
    both: bool = False,
) -> npt.NDArray[np.float64]: ...
def optimise(
    program: Union[Program, StrPath],
    part: Union[Mesh, StrPath, None],
    stock: Optional[str],
    machine: Optional[StrPath],
    material: Optional[str],
    tools: Optional[str],
    flutes: Optional[int],
    vc: Optional[float],
    resolution: Optional[float],
    passes: Optional[str],
    limits: Optional[Dict[str, float]],
    dialect: Optional[str],
    output: Optional[StrPath],
    library: Union[ToolLibrary, StrPath, None] = None,
) -> Tuple[Program, str, Dict[str, Any], bool]: ...
def dialect_extension(dialect: str) -> str: ...
SIDES: List[str]
def speed(
    program: Union[Program, StrPath],
    part: Union[Mesh, StrPath],
    vc: float,
    fz: float,
    ap: float,
    flutes: Optional[int] = None,
    machine: Optional[StrPath] = None,
    ball_d: Optional[float] = None,
    keep_feed: bool = False,
    s_threshold: Optional[float] = None,
    convention: Optional[str] = None,
    normals: Optional[str] = None,
) -> Tuple[Program, Dict[str, npt.NDArray[Any]], Dict[str, Any]]:
    """The speed pass: new program, per-point columns (uncut_side as codes
    into SIDES), the report of ``millplan speed --json``."""
def gouge(
    program: Union[Program, StrPath],
    part: Union[Mesh, StrPath],
    tol: Optional[float] = None,
    step: Optional[float] = None,
    rapids: bool = False,
    tools: Optional[str] = None,
) -> Dict[str, Any]:
    """The gouge check's report, as ``millplan gouge --json``."""
def simulate(
    program: Union[Program, StrPath],
    stock: str,
    part: Union[Mesh, StrPath, None] = None,
    machine: Optional[StrPath] = None,
    tools: Optional[str] = None,
    holder: Optional[str] = None,
    flute_length: Optional[float] = None,
    shank: Optional[float] = None,
    resolution: Optional[float] = None,
    tol: Optional[float] = None,
    mesh_resolution: Optional[float] = None,
    output: Optional[StrPath] = None,
) -> Tuple[Dict[str, npt.NDArray[Any]], Dict[str, Any]]:
    """Per-move columns and the report of ``millplan simulate --json``."""
def force(
    program: Union[Program, StrPath],
    stock: str,
    material: str,
    part: Union[Mesh, StrPath, None] = None,
    machine: Optional[StrPath] = None,
    tools: Optional[str] = None,
    flutes: Optional[int] = None,
    resolution: Optional[float] = None,
) -> Tuple[Dict[str, npt.NDArray[Any]], Dict[str, Any]]:
    """Per-move load columns and the counts and maxima of ``millplan force --json``."""
def cut(
    tool: str,
    fz: float,
    ap: float,
    n: float,
    ae: Optional[float] = None,
    material: Optional[str] = None,
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
) -> Tuple[Dict[str, Any], Dict[str, npt.NDArray[np.float64]]]:
    """The figures of ``millplan cut --json`` and the curves over a revolution."""
def raster(
    part: Union[Mesh, StrPath],
    tool: str,
    stepover: float,
    step: float,
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
) -> Tuple[Program, Dict[str, Any]]:
    """The raster program and the report of ``millplan raster --json``."""
def reorder(
    program: Union[Program, StrPath],
    part: Union[Mesh, StrPath],
    method: Optional[str] = None,
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
) -> Tuple[Program, Dict[str, Any]]:
    """The reordered program and the summary of ``millplan reorder --json``."""
def feed(
    program: Union[Program, StrPath],
    stock: str,
    material: str,
    part: Union[Mesh, StrPath, None] = None,
    machine: Optional[StrPath] = None,
    tools: Optional[str] = None,
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
) -> Tuple[Program, str, Dict[str, Any], Dict[str, npt.NDArray[Any]]]:
    """The feed pass: the new program, its text, the summary of ``millplan
    feed --json`` and the input's per-move loads with the feeds allowed."""
def setup(
    part: Union[Mesh, StrPath],
    machine: Optional[StrPath] = None,
    kind: Optional[str] = None,
    range1: Optional[str] = None,
    range2: Optional[str] = None,
    grid: Optional[str] = None,
    cells: Optional[int] = None,
    tool: Optional[str] = None,
    clearance: Optional[float] = None,
    ignore_bottom: bool = False,
    exact: bool = False,
) -> Tuple[Dict[str, Any], Mesh]:
    """The report of ``millplan setup --json`` and the part rotated into the setup."""
def post(
    program: Union[Program, StrPath],
    machine: StrPath,
    output: Optional[StrPath] = None,
    dialect: Optional[str] = None,
    tcp: bool = False,
    g93: bool = False,
    tol: Optional[float] = None,
    pole_cone: Optional[float] = None,
    pole_tol: Optional[float] = None,
    clearance: Optional[float] = None,
    force: bool = False,
) -> Tuple[Program, str, Dict[str, Any]]:
    """The posted program, its text and the summary of ``millplan post --json``."""
