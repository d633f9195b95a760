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
) -> Tuple[Program, str, Dict[str, Any], bool]: ...
def dialect_extension(dialect: str) -> str: ...
