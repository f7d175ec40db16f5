"""crest: predicted 5-axis ball-end machined surfaces from tool paths (Python face).

Everything runs in the crest library (no subprocess); long computations release the GIL.
Units: mm for lengths, µm for heights, degrees for angles, mm/min for feeds.
"""

from os import PathLike
from typing import Any, Dict, Iterable, List, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

StrPath = Union[str, "PathLike[str]"]

class CrestError(Exception):
    """Bad input (the message names file, line and column) or a failed computation; the
    message is the command line's."""

    file: Optional[str]
    """The input the error names, when it names a place in one."""
    line: Optional[int]
    """The 1-based line of that place (None when the error names none)."""
    column: Optional[int]
    """The 1-based column, in characters (None when the error names none)."""

class Cutter:
    """A cutter as crest reads it from a ``tool.toml``.

    ``Cutter(shape="ball", radius_mm=5.0, teeth=2)`` writes the keyword arguments as a
    ``tool.toml`` (a dict value becomes a table, e.g. ``runout={...}``) and checks them with
    the file's rules and messages; ``Cutter.from_toml(path)`` reads a file.
    """

    toml: str
    """The tool.toml text the cutter was read from."""
    source: str
    """Its file name, or ``"<keyword arguments>"``."""
    radius_mm: float
    """Nominal radius, mm."""
    teeth: int
    """Number of teeth."""
    def __init__(self, **kwargs: Any) -> None: ...
    @staticmethod
    def from_toml(path: StrPath) -> "Cutter":
        """Read a ``tool.toml``."""
    @staticmethod
    def from_text(text: str, file: str = "<text>") -> "Cutter":
        """Read ``tool.toml`` text; ``file`` names it in error messages."""
    def analyse(self, lead_deg: float, ap_mm: float, fz_mm: float, rule: str = "exact") -> Dict[str, Any]:
        """The tool analysis of ``crest tool --json`` (same keys, same values): effective
        radius, crest height, participating teeth (``rule`` "exact" or "paper")."""

def read_map(
    path: StrPath,
    dx_um: Optional[float] = None,
    dy_um: Optional[float] = None,
    channel: Optional[str] = None,
) -> "HeightMap":
    """Read a measured or written height map, as ``HeightMap.read`` does (the same object):
    .csv, .xyz/.txt, .gsf, .sdf, .x3p, .sur, .al3d, .gwy, .plu, .plux, .opd, .vk4."""

class HeightMap:
    """Heights in µm on a regular grid: ``z_um[row, col]``, rows along y ascending, NaN where
    no tooth reached; node (0, 0) at ``origin_mm`` in the grid's frame. Picklable (exact
    round trip)."""

    def __init__(
        self,
        z_um: npt.NDArray[np.float64],
        dx_um: float,
        dy_um: Optional[float] = None,
        x0_mm: float = 0.0,
        y0_mm: float = 0.0,
    ) -> None: ...
    @staticmethod
    def read(
        path: StrPath,
        dx_um: Optional[float] = None,
        dy_um: Optional[float] = None,
        channel: Optional[str] = None,
    ) -> "HeightMap":
        """Read a height map: .csv, .xyz/.txt, .gsf, .sdf, .x3p, or an instrument's own
        .sur, .al3d, .gwy, .plu, .plux, .opd, .vk4 (told by content where it has a magic);
        ``channel`` names a .gwy channel by its title."""
    z_um: npt.NDArray[np.float64]
    """Heights, µm, shape (ny, nx) (a copy)."""
    nx: int
    ny: int
    dx_um: float
    """Spacing along x, µm."""
    dy_um: float
    """Spacing along y, µm."""
    origin_mm: Tuple[float, float]
    """(x0, y0) of node (0, 0), mm."""
    x_mm: npt.NDArray[np.float64]
    """x of each column, mm."""
    y_mm: npt.NDArray[np.float64]
    """y of each row, mm."""
    def to_gsf(self, path: StrPath) -> None:
        """Write Gwyddion Simple Field (metres, float32), as ``crest simulate -o X.gsf``."""
    def to_sdf(self, path: StrPath) -> None:
        """Write ISO 25178-71 SDF (metres), as ``crest simulate -o X.sdf``."""
    def to_csv(self, path: StrPath) -> None:
        """Write grid CSV (µm, one line per row), as ``crest simulate -o X.csv``."""
    def metrics(
        self,
        params: Optional[str] = None,
        *,
        level: str = "none",
        lambda_s_um: Optional[float] = None,
        lambda_c_um: Optional[float] = None,
        ends: str = "reflect",
        profile: Optional[str] = None,
        sections: int = 5,
    ) -> Dict[str, float]:
        """Parameters of this map; see :func:`metrics`."""

class PartMap:
    """A simulated part map: points on the design surface and heights along their normals.
    Picklable (exact round trip)."""

    def __init__(
        self,
        points: npt.NDArray[np.float64],
        normals: npt.NDArray[np.float64],
        height_um: npt.NDArray[np.float64],
        nodes_cut: int = 0,
    ) -> None: ...

    points: npt.NDArray[np.float64]
    """(N, 3) part points, mm."""
    normals: npt.NDArray[np.float64]
    """(N, 3) unit normals."""
    height_um: npt.NDArray[np.float64]
    """(N,) heights above the design surface, µm (NaN = not reached)."""
    nodes_cut: int

def read_path(file: StrPath, *, absolute: bool = False) -> List[Dict[str, Any]]:
    """Read a tool-path file (NX CLSF, other APT, contact12; chosen by content) into one dict
    per tool path: ``name``, ``tool_name``, ``tip`` and ``axis`` (N×3), ``motion`` (list of
    "from"/"rapid"/"cut"/"cycle"/"gohome"), ``feed_mm_min``, ``spindle_rpm`` (N, NaN before
    the first FEDRAT/SPINDL), ``line`` (N), ``contact`` and ``normal`` (N×3, NaN without
    contact data). ``absolute`` applies MSYS."""

def metrics(
    map: Union[HeightMap, StrPath],
    params: Optional[str] = None,
    *,
    level: str = "none",
    lambda_s_um: Optional[float] = None,
    lambda_c_um: Optional[float] = None,
    ends: str = "reflect",
    profile: Optional[str] = None,
    sections: int = 5,
    dx_um: Optional[float] = None,
    dy_um: Optional[float] = None,
) -> Dict[str, float]:
    """Profile or ISO 25178 areal parameters, as ``crest metrics --json``: symbol → value (µm,
    degrees, %; NaN where undefined). ``params`` a comma list (default all); ``level``
    "none", "plane" or "poly:N"; ``profile`` "row:K", "col:K" or "angle:DEG"."""

def simulate(
    file: StrPath,
    *,
    tool: Union[Cutter, StrPath, None] = None,
    window: Optional[Tuple[float, float, float, float]] = None,
    patch_at: Optional[float] = None,
    patch_near: Optional[Tuple[float, float, float]] = None,
    patch_mm: Optional[Tuple[float, float]] = None,
    map_mm: Optional[float] = None,
    region: Optional[Tuple[float, float, float, float, float, float]] = None,
    part: Optional[StrPath] = None,
    process: Optional[StrPath] = None,
    rpm: Optional[float] = None,
    feed_mm_min: Optional[float] = None,
    fz_mm: Optional[float] = None,
    feed: Optional[str] = None,
    machine: Optional[StrPath] = None,
    model: str = "ice",
    dtheta_deg: float = 1.0,
    grid_um: Optional[float] = None,
    chord_tol_um: Optional[float] = None,
    band_um: Optional[float] = None,
    ap_mm: Optional[float] = None,
    path: Optional[int] = None,
    teeth: Optional[int] = None,
    helix_deg: Optional[float] = None,
    absolute: bool = False,
) -> Union[HeightMap, PartMap]:
    """Simulate the surface a tool path leaves, as ``crest simulate`` with the same options:
    exactly one of ``window`` (mm, WCS), ``patch_at``/``patch_near`` with ``patch_mm``, or
    ``map_mm`` (a part map; needs ``part``). ``tool`` is a :class:`Cutter` or the path of a
    ``tool.toml`` (default: the file's TLDATA with ``teeth``). Releases the GIL."""

def resample(
    file: StrPath,
    *,
    mode: str,
    fz_mm: float,
    teeth: int,
    dtheta_deg: float = 0.5,
    rpm: Optional[float] = None,
    feed_mm_min: Optional[float] = None,
    axis: str = "slerp",
    spline: bool = False,
    path: Optional[int] = None,
) -> Dict[str, npt.NDArray[Any]]:
    """Resample the cutting moves as ``crest resample`` (programmed feed): ``mode`` "fz" or
    "dtheta". A dict of arrays with the CSV's columns (``s_mm``, ``t_s``, ``theta_deg``,
    ``x``…``z``, ``i``…``k``, ``cx``…``cz``, ``nx``…``nz`` (NaN without contact data),
    ``fx``…``fz``, ``feed_mm_min``) and ``path`` (0-based), at full precision."""

def plan_feed(file: StrPath, machine: StrPath, *, level: str = "jerk", absolute: bool = False) -> List[Dict[str, Any]]:
    """Plan the feed the machine reaches, as ``crest feed``: one dict per tool path with
    ``name``, ``total_time_s``, ``programmed_time_s``, ``self_check_ok`` and per posture
    ``t_s``, ``feed_mm_min``, ``path_speed_mm_min``, ``line`` (numpy arrays). Releases the GIL."""

def study_tasks(
    design: str, *, monte_carlo: Optional[int] = None, seed: int = 1
) -> List[Dict[str, Any]]:
    """The tasks of a designed experiment (a ``crest study`` design file path, or its TOML
    text with ``tool`` relative to the working directory): one plain dict per run. With
    ``monte_carlo=N`` every task also computes the P5/P50/P95 bands of its responses over N
    samples of ``seed`` (``crest study --monte-carlo N --seed S``); merged, they give that
    command's bytes."""

def map_tasks(
    file: StrPath,
    *,
    tasks: int,
    map_mm: float,
    part: StrPath,
    region: Optional[Tuple[float, float, float, float, float, float]] = None,
    tool: Union[Cutter, StrPath, None] = None,
    process: Optional[StrPath] = None,
    rpm: Optional[float] = None,
    feed_mm_min: Optional[float] = None,
    fz_mm: Optional[float] = None,
    feed: Optional[str] = None,
    machine: Optional[StrPath] = None,
    model: str = "ice",
    dtheta_deg: float = 1.0,
    grid_um: Optional[float] = None,
    chord_tol_um: Optional[float] = None,
    band_um: Optional[float] = None,
    ap_mm: Optional[float] = None,
    path: Optional[int] = None,
    teeth: Optional[int] = None,
    helix_deg: Optional[float] = None,
    absolute: bool = False,
) -> List[Dict[str, Any]]:
    """The tile tasks of a part map (the options of :func:`simulate` with ``map_mm``):
    ``tasks`` plain dicts, task k simulating cells k, k+tasks, … of the map. File paths are
    made absolute; every worker must see the files there."""

def atlas_tasks(
    file: StrPath,
    *,
    tasks: int,
    every_mm: float,
    patch_mm: Optional[Tuple[float, float]] = None,
    part: Optional[StrPath] = None,
    tool: Union[Cutter, StrPath, None] = None,
    process: Optional[StrPath] = None,
    rpm: Optional[float] = None,
    feed_mm_min: Optional[float] = None,
    fz_mm: Optional[float] = None,
    model: str = "dome",
    dtheta_deg: float = 1.0,
    grid_um: Optional[float] = None,
    chord_tol_um: Optional[float] = None,
    band_um: Optional[float] = None,
    ap_mm: Optional[float] = None,
    path: Optional[int] = None,
    teeth: Optional[int] = None,
    helix_deg: Optional[float] = None,
    absolute: bool = False,
) -> List[Dict[str, Any]]:
    """The patch tasks of a roughness atlas (the options of ``crest atlas``): ``tasks``
    plain dicts, task k simulating patches k, k+tasks, … . :func:`merge` of their results
    gives a dict with ``rows``, ``regions`` and ``files`` (``atlas.csv``, the bytes ``crest
    atlas`` writes). File paths are made absolute; every worker must see the files there."""

def runout_tasks(study: str, *, tasks: Optional[int] = None) -> List[Dict[str, Any]]:
    """The tasks of a run-out sweep (a ``crest runout`` study file path, or its TOML text
    with ``tool`` relative to the working directory): one plain dict per case of the sweep,
    or with ``tasks`` that many, task k evaluating cases k-1, k-1+tasks, … (0-based, the
    cases of ``runout.csv``). A task carries the study and tool texts."""

def run_task(task: Union[Dict[str, Any], str]) -> Dict[str, Any]:
    """Run one task (a dict from :func:`study_tasks`, :func:`runout_tasks` or
    :func:`map_tasks`, or its JSON); returns a plain dict (a study run: responses, fz_mm,
    stepover_mm, error; a run-out task: its cases' numbers; a map task: its cells' points
    and heights). Releases the GIL."""

def merge(
    results: Iterable[Union[Dict[str, Any], str]], output: Optional[StrPath] = None
) -> Union[Dict[str, Any], PartMap]:
    """Assemble every task result of one design (any order) as ``crest study`` does: a dict
    with ``title``, ``runs``, ``effects`` (as ``crest study --json``) and ``files`` (name →
    bytes of runs.csv, effects.csv and the charts, identical to ``crest study``'s); with
    ``output`` the files are written there too. The results of one part map's
    :func:`map_tasks` give the :class:`PartMap` of :func:`simulate`; with ``output`` (a
    .ply path) the PLY ``crest simulate`` writes, byte for byte. The results of one run-out
    sweep's :func:`runout_tasks` give a dict with ``rule``, ``x``, ``tool``, ``rows`` (as
    ``crest runout --json``) and ``files`` (name → bytes of runout.csv and the charts,
    identical to ``crest runout``'s); with ``output`` the files are written there too."""
