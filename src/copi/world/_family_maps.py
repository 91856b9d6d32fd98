"""The ``maps`` world family: windows of Moving AI grid maps, scaled for disc agents."""

from __future__ import annotations

import functools
import hashlib
import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import shapely
from scipy import ndimage
from shapely.geometry import Polygon

from copi._rng import Seed, as_generator
from copi.errors import InvalidArgumentError, InvalidWorldError
from copi.world._world import ObstacleSpec, World
from copi.world.gridmap import free_geometry, read_map, without_pinches

__all__ = [
    "MOVINGAI_ENV",
    "MapsParams",
    "PACKAGED_MAPS",
    "map_window_world",
    "maps_identity",
    "movingai_dir",
    "shipped_map",
    "shipped_maps",
]

MOVINGAI_ENV = "COPI_MOVINGAI"
"""Environment variable naming another directory of Moving AI maps."""

MAX_PASSAGE = 100.0
"""Widest a map's passages may be scaled to, agent steps (the sensor reaches 10: wider
passages make a world of empty halls, and far wider ones overflow the geometry)."""

PACKAGED_MAPS = Path(__file__).resolve().parents[1] / "data" / "movingai"
"""The ten Moving AI maps copi ships (their provenance and licence beside them)."""


def shipped_maps() -> dict[str, Path]:
    """The Moving AI maps copi ships, by file name (``room-32-32-4.map``: its path)."""
    return {p.name: p for p in sorted(PACKAGED_MAPS.rglob("*.map"))}


def shipped_map(path: str | os.PathLike[str]) -> Path:
    """``path``, or when no such file is there and it names one of the maps copi ships
    (:func:`shipped_maps`, with or without ``.map``), that map's path.

    Examples
    --------
    >>> shipped_map("room-32-32-4.map").relative_to(PACKAGED_MAPS).as_posix()
    'mapf/room-32-32-4.map'
    """
    p = Path(path)
    if p.exists() or p.parent != Path("."):
        return p
    ours = shipped_maps()
    name = p.name if p.suffix == ".map" else f"{p.name}.map"
    return ours.get(name, p)


def movingai_dir(data_dir: str | os.PathLike[str] | None = None) -> Path:
    """The directory of Moving AI ``.map`` files the ``maps`` family draws from (searched
    recursively).

    ``data_dir`` when given; else ``$COPI_MOVINGAI`` when set; else the maps shipped with
    copi (:data:`PACKAGED_MAPS`: ten maps of the Moving AI benchmarks, see the README
    beside them). A directory given (argument or variable) must hold a ``.map`` file.

    Raises
    ------
    InvalidArgumentError
        When the directory given holds no map, naming it and where it came from.

    Examples
    --------
    >>> movingai_dir() == PACKAGED_MAPS  # with $COPI_MOVINGAI unset
    True
    """
    if data_dir is not None:
        path, why = Path(data_dir), "data_dir"
    elif os.environ.get(MOVINGAI_ENV):
        path, why = Path(os.environ[MOVINGAI_ENV]), f"${MOVINGAI_ENV}"
    else:
        path, why = PACKAGED_MAPS, "the maps copi ships"
    if path.is_dir() and next(path.rglob("*.map"), None) is not None:
        return path
    what = "is not a directory" if not path.is_dir() else "holds no Moving AI map (*.map)"
    raise InvalidArgumentError(
        f"{path} ({why}) {what}; the maps family needs a directory of .map files"
        + (f" (unset ${MOVINGAI_ENV} to use the maps copi ships)" if why != "data_dir" else "")
    )


def maps_identity(data_dir: str | os.PathLike[str] | None = None) -> str:
    """The content hash of the map set the ``maps`` family draws from: every ``.map``
    file's path relative to :func:`movingai_dir` and its SHA-256, in the order the family
    draws them. A run of the ``maps`` family records it, so that results drawn from
    another map set never resume into it.

    Examples
    --------
    >>> len(maps_identity()), maps_identity() == maps_identity(PACKAGED_MAPS)
    (64, True)
    """
    root = movingai_dir(data_dir)
    return _identity(str(root), tuple(_stamps(root)))


def _stamps(root: Path) -> list[tuple[str, int, int]]:
    """(path, size, mtime) of each map: a changed file misses the cache below."""
    out = []
    for p in _map_files(str(root)):
        st = os.stat(p)
        out.append((p, st.st_size, st.st_mtime_ns))
    return out


@functools.lru_cache(maxsize=8)
def _identity(root: str, stamps: tuple[tuple[str, int, int], ...]) -> str:
    h = hashlib.sha256()
    for path, _, _ in stamps:
        rel = Path(path).relative_to(root).as_posix()
        h.update(rel.encode() + b"\0")
        with open(path, "rb") as fh:
            h.update(hashlib.sha256(fh.read()).digest())
    return h.hexdigest()


@dataclass(frozen=True)
class MapsParams:
    """The distribution of :func:`map_window_world`.

    A map is drawn uniformly among the ``.map`` files of the data directory, then a square
    window of it uniformly. The map is scaled so that its narrow passages are ``passage``
    agent steps wide (narrow: the 10th percentile of the free space's width along its
    medial axis, measured on the grid with a Euclidean distance transform), and at least
    so that the whole map spans ``min_extent``. Moving obstacles get radii that fit those
    passages (at most 0.3 of their width, and at most the paper's 1.0) and a count that
    follows the free area (about one per 90 square agent steps, as in the paper's worlds).
    """

    data_dir: str | None = None
    """Directory of ``.map`` files; None looks where :func:`movingai_dir` says."""
    window: tuple[float, float] = (40.0, 60.0)
    """Side of the square window, in agent steps, uniform (at most 0.85 of the map's
    side, so that a small map still gives different worlds)."""
    passage: float = 3.0
    """Width, in agent steps, that the map's narrow passages are scaled to."""
    min_extent: float = 40.0
    """Least size of the scaled map's shorter side, in agent steps."""
    agent_radius: float = 0.3
    """Windows whose free space falls apart for an agent of this radius are redrawn (the
    largest piece of free space is kept; walls cut off the rest)."""

    def __post_init__(self) -> None:
        if not (0 < self.window[0] <= self.window[1]):
            raise InvalidArgumentError(f"window must satisfy 0 < low <= high; got {self.window}")
        for key in ("passage", "min_extent"):
            if not getattr(self, key) > 0:
                raise InvalidArgumentError(f"{key} must be > 0; got {getattr(self, key)}")
        if not self.agent_radius >= 0:
            raise InvalidArgumentError(f"agent_radius must be >= 0; got {self.agent_radius}")


@dataclass(frozen=True)
class _Map:
    name: str
    free: shapely.Geometry
    """Free space in cell units (y up), as :func:`free_geometry` gives it."""
    height: int
    width: int
    passage_cells: float
    """10th percentile of 2 x the distance to the nearest blocked cell on ridge cells."""


@functools.lru_cache(maxsize=64)
def _load(path: str) -> _Map:
    grid = read_map(path)
    free = grid.free
    dist = ndimage.distance_transform_edt(np.pad(free, 1))[1:-1, 1:-1]
    ridge = free & (dist >= ndimage.maximum_filter(dist, size=3))
    width = 2.0 * dist[ridge]
    passage = float(np.percentile(width, 10)) if width.size else 1.0
    return _Map(Path(path).stem, free_geometry(grid), grid.height, grid.width, passage)


def _map_files(directory: str) -> tuple[str, ...]:
    # not cached: the set may change between calls (and listing it costs ~0.1 ms)
    return tuple(sorted(str(p) for p in Path(directory).rglob("*.map")))


def map_window_world(
    seed: Seed = None, *, params: MapsParams | None = None, name: str | None = None
) -> World:
    """Draw a world of the ``maps`` family (see :class:`MapsParams`): a window of a Moving
    AI map, scaled, with obstacles sized to its passages.

    Parsed maps are cached (per file path), so only the first world of a map pays for
    reading it.

    Raises
    ------
    InvalidArgumentError
        When the data directory holds no map (see :func:`movingai_dir`).
    InvalidWorldError
        When 100 windows in a row give no usable world.
    """
    rng = as_generator(seed)
    p = params or MapsParams()
    files = _map_files(str(movingai_dir(p.data_dir)))
    for _ in range(100):
        m = _load(files[int(rng.integers(len(files)))])
        scale = max(p.passage / m.passage_cells, p.min_extent / min(m.height, m.width))
        side = rng.uniform(*p.window) / scale
        # whole cells (a window edge through a cell would leave slivers and half doors);
        # a small map gives windows of at most 0.85 of it, so that worlds still differ
        wx = max(1, round(min(side, 0.85 * m.width)))
        wy = max(1, round(min(side, 0.85 * m.height)))
        x0, y0 = int(rng.integers(0, m.width - wx + 1)), int(rng.integers(0, m.height - wy + 1))
        world = _window(m, x0, y0, wx, wy, scale, p.agent_radius, name)
        if world is not None:
            return world
    raise InvalidWorldError(f"no usable window found in 100 draws from {len(files)} maps")


def scaled_map_world(
    path: str | os.PathLike[str],
    *,
    passage: float = 3.0,
    agent_radius: float = 0.3,
    name: str | None = None,
) -> World:
    """A whole Moving AI map as a world for disc agents: scaled so that its narrow
    passages are ``passage`` agent steps wide (as the ``maps`` family scales its windows),
    keeping its largest free region, with moving obstacles sized to those passages.

    One cell of a Moving AI map is one unit of its scenarios; at that scale a one-cell
    door barely lets the agent through and no moving obstacle of the paper's size (radius
    0.5-1.0) at all, so navigation experiments want the map scaled.

    Raises
    ------
    InvalidWorldError
        When the scaled map has too little room for tasks (a task needs two free points
        10 apart).
    """
    if not (math.isfinite(passage) and 0 < passage <= MAX_PASSAGE):
        raise InvalidArgumentError(f"passage must be a number in (0, {MAX_PASSAGE:g}] agent "
                                   f"steps; got {passage!r}")  # fmt: skip
    m = _load(os.fspath(path))
    scale = passage / m.passage_cells
    world = _window(m, 0, 0, m.width, m.height, scale, agent_radius, name or m.name)
    if world is None:
        raise InvalidWorldError(
            f"{path}: scaled so that its passages are {passage:g} wide, the map leaves too "
            "little room for tasks (try a larger --passage)"
        )
    return world


def _window(
    m: _Map,
    x0: int,
    y0: int,
    wx: int,
    wy: int,
    scale: float,
    agent_radius: float,
    name: str | None,
) -> World | None:
    cut = shapely.intersection(m.free, shapely.box(x0, y0, x0 + wx, y0 + wy))
    cut = shapely.affinity.affine_transform(cut, [scale, 0, 0, scale, -scale * x0, -scale * y0])
    cut = without_pinches(cut)
    parts = [g for g in shapely.get_parts(cut) if isinstance(g, Polygon) and g.area > 0]
    if not parts:
        return None
    region = shapely.simplify(max(parts, key=lambda g: g.area), 0.0)
    if not isinstance(region, Polygon):
        return None
    # start, goal and obstacles are drawn in one connected piece of free space, so the
    # space the agent can use must not fall apart (same erosion as the simulator's)
    usable = region.buffer(-agent_radius, quad_segs=8)
    if not isinstance(usable, Polygon) or usable.area < 150.0:
        return None
    lo, hi = np.min(usable.exterior.coords, axis=0), np.max(usable.exterior.coords, axis=0)
    if np.hypot(*(hi - lo)) < 20.0:
        return None
    passage = scale * m.passage_cells
    r_hi = min(1.0, 0.3 * passage)
    count = int(np.clip(round(region.area / 90.0), 4, 10))
    radius = (round(min(0.5, 0.5 * r_hi), 3), round(r_hi, 3))
    spec = ObstacleSpec(count=(count, count + 5), radius=radius)
    label = name or f"maps-{m.name}-x{x0}-y{y0}-{wx}x{wy}"
    try:
        return World(
            np.round(np.asarray(region.exterior.coords)[:-1], 6),
            tuple(np.round(np.asarray(r.coords)[:-1], 6) for r in region.interiors),
            name=label,
            obstacles=spec,
        )
    except InvalidWorldError:
        return None
