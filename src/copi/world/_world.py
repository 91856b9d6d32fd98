"""The static world: a polygon with holes, validated once and never changed."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import shapely
from shapely.geometry import LinearRing, Polygon

from copi._validation import FloatArray, as_vector
from copi.errors import CopiError, InvalidWorldError
from copi.geometry import as_ring, clearance, orient, ring_crossings, ring_segments

__all__ = ["BEHAVIOURS", "ObstacleSpec", "World"]


@contextmanager
def _at(*where: str | int) -> Iterator[None]:
    """Attach the JSON path ``where`` to errors raised inside (unless they have one)."""
    try:
        yield
    except CopiError as exc:
        if isinstance(exc, InvalidWorldError) and exc.where:
            raise
        raise InvalidWorldError(str(exc), where=where) from None


MAX_VERTICES = 100_000
"""Most vertices a world may have, boundary and holes together (copi's families draw at
most a few hundred; a Moving AI map of 512 x 512 cells, a few thousand)."""
MAX_COORDINATE = 1e6
"""Largest absolute coordinate of a world, in agent steps (the agent moves 1 a step; a
world of 1e300 is a typing error, and its arithmetic overflows)."""
BEHAVIOURS = ("random-walk", "orca", "hl", "hrvo", "social-force")
"""How moving obstacles may move (:attr:`ObstacleSpec.behaviour`)."""

MAX_OBSTACLES = 10_000
"""More moving obstacles than this in one world are refused (a typo, not a crowd)."""


def _pair(value: Any, name: str, *, integer: bool = False) -> tuple[float, float]:
    """A number or a [lo, hi] pair as (lo, hi), checked finite, ordered and >= 0."""
    if isinstance(value, bool):
        raise InvalidWorldError(f"{name} must be a number or a [low, high] pair; got {value!r}")
    if isinstance(value, int | float | np.integer | np.floating):
        try:
            lo = hi = float(value)
        except OverflowError:
            raise InvalidWorldError(f"{name} is too large for a float") from None
    elif isinstance(value, list | tuple) and len(value) == 2:
        try:
            lo, hi = float(value[0]), float(value[1])
        except (TypeError, ValueError, OverflowError):
            raise InvalidWorldError(
                f"{name} must be a number or a [low, high] pair; got {value!r}"
            ) from None
    else:
        raise InvalidWorldError(f"{name} must be a number or a [low, high] pair; got {value!r}")
    if not (np.isfinite(lo) and np.isfinite(hi)) or lo < 0 or hi < lo:
        raise InvalidWorldError(f"{name} must be finite with 0 <= low <= high; got {value!r}")
    if integer and (lo != int(lo) or hi != int(hi)):
        raise InvalidWorldError(f"{name} must be whole numbers; got {value!r}")
    return lo, hi


@dataclass(frozen=True)
class ObstacleSpec:
    """How many moving obstacles a world has, how large and how fast (paper §IV), and how
    they move.

    Defaults are the paper's: 10 to 15 discs random-walking at 0.6 of the agent's speed;
    radii from 0.5 to 1.0 agent steps (the paper does not give sizes; docs/design.md does).
    A crowd ``behaviour`` makes them walk toward goals of their own instead, each step
    chosen by one of navground's behaviours (ORCA, HL, HRVO, social force: the extra
    ``peers``), avoiding each other, the walls and, when ``sees_agent``, the agent.
    """

    count: tuple[int, int] = (10, 15)
    """Number of obstacles, drawn uniformly from the inclusive range (low, high)."""
    radius: tuple[float, float] = (0.5, 1.0)
    """Disc radius in agent steps, drawn uniformly from (low, high) for each obstacle."""
    speed: float = 0.6
    """Distance moved per time step, in agent steps (the agent moves at most 1); a crowd
    behaviour's preferred speed."""
    behaviour: str = "random-walk"
    """How they move: "random-walk" (the paper's: each ignores everything), or toward goals
    of their own with navground's "orca", "hl", "hrvo" or "social-force"."""
    sees_agent: bool = False
    """A crowd sees the agent and gives way to it; otherwise the agent is invisible to it
    (CrowdNav's setting)."""
    time_horizon: float = 10.0
    """Steps ahead a crowd behaviour looks (ORCA's and HRVO's time horizon)."""
    safety_margin: float = 0.0
    """Room a crowd behaviour keeps beyond the sum of radii, agent steps."""
    neighbours: int = 10
    """Most neighbours a crowd behaviour considers, the nearest first."""
    sight: float = 10.0
    """How far a crowd behaviour sees the others, agent steps (navground's state
    estimation range; for ORCA also its neighbour distance)."""
    new_goals: bool = True
    """A disc at its goal is given another (drawn in the free space); otherwise it stays."""
    positions: tuple[tuple[float, float], ...] | None = None
    """Where the discs start (then ``count`` is their number): drawn when None."""
    goals: tuple[tuple[float, float], ...] | None = None
    """A crowd's first goals, one per disc: drawn when None."""

    def __post_init__(self) -> None:
        self._crowd_checks()
        lo, hi = _pair(self.count, "obstacles.count", integer=True)
        if hi > MAX_OBSTACLES:
            raise InvalidWorldError(
                f"obstacles.count must be at most {MAX_OBSTACLES}; got {self.count!r}"
            )
        object.__setattr__(self, "count", (int(lo), int(hi)))
        r = _pair(self.radius, "obstacles.radius")
        if r[0] <= 0:
            raise InvalidWorldError(f"obstacles.radius must be > 0; got {self.radius!r}")
        object.__setattr__(self, "radius", r)
        speed = _pair(self.speed, "obstacles.speed")
        if speed[0] != speed[1]:
            raise InvalidWorldError(f"obstacles.speed must be one number; got {self.speed!r}")
        object.__setattr__(self, "speed", speed[0])
        if self.positions is not None:  # the discs given: their number is the count
            object.__setattr__(self, "count", (len(self.positions), len(self.positions)))

    def _crowd_checks(self) -> None:
        if self.behaviour not in BEHAVIOURS:
            raise InvalidWorldError(f"obstacles.behaviour must be one of "
                                    f"{', '.join(BEHAVIOURS)}; got {self.behaviour!r}")  # fmt: skip
        for key in ("sees_agent", "new_goals"):
            if not isinstance(getattr(self, key), bool):
                raise InvalidWorldError(f"obstacles.{key} must be true or false; got "
                                        f"{getattr(self, key)!r}")  # fmt: skip
        for key, most in (("time_horizon", 1000.0), ("safety_margin", 100.0),
                          ("sight", 1000.0)):  # fmt: skip
            v = getattr(self, key)
            ok = isinstance(v, int | float) and not isinstance(v, bool) and np.isfinite(v)
            low = key == "safety_margin"  # 0 allowed
            if not ok or not (0 <= v <= most if low else 0 < v <= most):
                raise InvalidWorldError(f"obstacles.{key} must be a number in "
                                        f"{'[0' if low else '(0'}, {most:g}]; "
                                        f"got {v!r}")  # fmt: skip
            object.__setattr__(self, key, float(v))
        n = self.neighbours
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or not 1 <= n <= 1000:
            raise InvalidWorldError(f"obstacles.neighbours must be an int in 1 .. 1000; got {n!r}")
        for key in ("positions", "goals"):
            v = getattr(self, key)
            if v is None:
                continue
            try:
                arr = np.asarray(v, dtype=np.float64)
            except (TypeError, ValueError):
                arr = np.zeros((0, 3))
            if arr.ndim != 2 or arr.shape[1] != 2 or not len(arr) or not np.isfinite(arr).all():
                raise InvalidWorldError(f"obstacles.{key} must be a list of [x, y] points; got "
                                        f"{v!r}"[:200])  # fmt: skip
            if (np.abs(arr) > MAX_COORDINATE).any():
                raise InvalidWorldError(f"obstacles.{key} lie beyond {MAX_COORDINATE:g}")
            object.__setattr__(self, key, tuple((float(x), float(y)) for x, y in arr))
        if self.goals is not None and self.behaviour == "random-walk":
            raise InvalidWorldError("obstacles.goals belong to a crowd behaviour; a random walk "
                                    "has none")  # fmt: skip
        if self.positions is not None and self.goals is not None and len(self.goals) != len(
                self.positions):  # fmt: skip
            raise InvalidWorldError(f"obstacles.goals must be one per position "
                                    f"({len(self.positions)}); got {len(self.goals)}")  # fmt: skip

    @property
    def reactive(self) -> bool:
        """The discs follow a crowd behaviour (not the paper's random walk)."""
        return self.behaviour != "random-walk"

    @classmethod
    def from_dict(cls, data: Any) -> ObstacleSpec:
        """From the JSON form ``{"count": 12, "radius": 0.75, "speed": 0.6}`` (all optional;
        count and radius may be [low, high] pairs), with, for a crowd, ``"behaviour":
        "orca"`` and its settings (``sees_agent``, ``time_horizon``, ``safety_margin``,
        ``neighbours``, ``sight``, ``new_goals``, ``positions``, ``goals``)."""
        if not isinstance(data, dict):
            raise InvalidWorldError(f"obstacles must be an object; got {type(data).__name__}")
        keys = [f.name for f in dataclasses.fields(cls)]
        unknown = sorted(set(data) - set(keys))
        if unknown:
            raise InvalidWorldError(
                f"obstacles has unknown keys {unknown}; expected {', '.join(keys)}"
            )
        default = cls()
        return cls(**{k: data.get(k, getattr(default, k)) for k in keys})

    def to_dict(self) -> dict[str, Any]:
        """JSON form; a (low, high) pair with low == high is written as one number."""

        def short(p: tuple[float, float] | tuple[int, int]) -> Any:
            return p[0] if p[0] == p[1] else list(p)

        out: dict[str, Any] = {"count": short(self.count), "radius": short(self.radius),
                               "speed": self.speed}  # fmt: skip
        default = type(self)()
        for f in dataclasses.fields(self):  # a crowd's settings, where they are not default
            v = getattr(self, f.name)
            if f.name not in out and v != getattr(default, f.name):
                out[f.name] = [list(p) for p in v] if f.name in ("positions", "goals") else v
        return out


@dataclass(frozen=True, eq=False)
class World:
    """A static navigation world: a simple polygon with polygonal holes (paper §IV).

    The geometry is validated on construction and normalised: the boundary is stored
    counter-clockwise, holes clockwise; arrays are read-only. Either orientation is
    accepted on input.

    Parameters
    ----------
    boundary : array_like of shape (n, 2)
        Vertices of the outer wall, a simple polygon, in agent steps.
    holes : sequence of array_like of shape (m, 2)
        Static obstacles: simple polygons strictly inside the boundary, pairwise disjoint.
    name : str
        A label used in files, tables and pictures.
    start, goal : array_like of shape (2,), optional
        A fixed task; drawn at random by the simulator when missing.
    obstacles : ObstacleSpec, optional
        Moving obstacles; the paper's distribution when missing.

    Raises
    ------
    InvalidWorldError
        Saying what is wrong and where, e.g. ``boundary must be a simple polygon; edges 0
        and 2 cross at (1.0, 1.0)``.

    Examples
    --------
    >>> w = World([[0, 0], [10, 0], [10, 10], [0, 10]], [[[4, 4], [6, 4], [6, 6], [4, 6]]])
    >>> w.area, w.segments.shape
    (96.0, (8, 4))
    >>> try:
    ...     World([[0, 0], [2, 2], [2, 0], [0, 2]])
    ... except InvalidWorldError as err:
    ...     print(err)
    world 'world': boundary must be a simple polygon; edges 0 and 2 cross at (1, 1)
    """

    boundary: FloatArray
    holes: tuple[FloatArray, ...] = ()
    name: str = "world"
    start: FloatArray | None = None
    goal: FloatArray | None = None
    obstacles: ObstacleSpec | None = None
    segments: FloatArray = field(init=False, repr=False)
    """All wall segments (boundary then holes), rows ``(px, py, qx, qy)``."""
    polygon: Polygon = field(init=False, repr=False)
    """The free space as a Shapely polygon (for sampling, drawing and reference checks)."""

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise InvalidWorldError(f"world name must be a non-empty string; got {self.name!r}")
        try:
            self._validate()
        except CopiError as exc:
            where = exc.where if isinstance(exc, InvalidWorldError) else ()
            raise InvalidWorldError(f"world {self.name!r}: {exc}", where=where) from None

    def _validate(self) -> None:
        holes_given = self.holes if self.holes is not None else ()
        try:
            n = len(self.boundary) + sum(len(h) for h in holes_given)
        except TypeError:
            n = 0  # not lists of vertices: the ring checks below say so
        if n > MAX_VERTICES:
            raise InvalidWorldError(
                f"a world may have at most {MAX_VERTICES:,} vertices (walls and holes "
                f"together); this one has {n:,}"
            )
        with _at("boundary"):
            boundary = _simple_ring(self.boundary, "boundary")
        if isinstance(self.holes, np.ndarray) and self.holes.ndim == 2:
            raise InvalidWorldError(
                "holes must be a list of polygons (each a list of [x, y]); got one polygon",
                where=("holes",),
            )
        given = []
        for k, h in enumerate(self.holes or ()):
            with _at("holes", k):
                given.append(_simple_ring(h, f"hole {k}"))
        holes = tuple(given)
        outer = Polygon(boundary)
        hole_polys = [Polygon(h) for h in holes]
        for k, hp in enumerate(hole_polys):
            if not outer.contains(hp):
                raise InvalidWorldError(_outside_message(k, holes[k], outer), where=("holes", k))
        if len(hole_polys) > 1:
            tree = shapely.STRtree(hole_polys)
            a, b = tree.query(hole_polys, predicate="intersects")
            pairs = [(int(i), int(j)) for i, j in zip(a, b, strict=True) if i < j]
            if pairs:
                i, j = pairs[0]
                where = hole_polys[i].intersection(hole_polys[j]).representative_point()
                raise InvalidWorldError(
                    f"holes must be disjoint; holes {i} and {j} meet at "
                    f"({where.x:.6g}, {where.y:.6g})",
                    where=("holes", j),
                )
        boundary = orient(boundary, ccw=True)
        holes = tuple(orient(h, ccw=False) for h in holes)
        polygon = Polygon(boundary, holes)
        if not polygon.is_valid:
            raise _invalid_message(outer, hole_polys, polygon)
        for ring in (boundary, *holes):
            ring.setflags(write=False)
        segments = np.ascontiguousarray(np.vstack([ring_segments(r) for r in (boundary, *holes)]))
        segments.setflags(write=False)
        object.__setattr__(self, "boundary", boundary)
        object.__setattr__(self, "holes", holes)
        object.__setattr__(self, "segments", segments)
        object.__setattr__(self, "polygon", polygon)
        for key in ("start", "goal"):
            value = getattr(self, key)
            if value is None:
                continue
            with _at(key):
                p = as_vector(value, key, length=2)
            if not shapely.contains_xy(polygon, p[0], p[1]):
                raise InvalidWorldError(
                    f"{key} ({p[0]:.6g}, {p[1]:.6g}) must lie in the free space "
                    "(inside the boundary, outside every hole)",
                    where=(key,),
                )
            p.setflags(write=False)
            object.__setattr__(self, key, p)
        if self.obstacles is not None and not isinstance(self.obstacles, ObstacleSpec):
            raise InvalidWorldError(
                f"obstacles must be an ObstacleSpec; got {type(self.obstacles).__name__}",
                where=("obstacles",),
            )

    # -- derived quantities ---------------------------------------------------------

    @property
    def area(self) -> float:
        """Area of the free space, in square agent steps."""
        return float(self.polygon.area)

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax) of the boundary."""
        b = self.boundary
        return (
            float(b[:, 0].min()),
            float(b[:, 1].min()),
            float(b[:, 0].max()),
            float(b[:, 1].max()),
        )

    def contains(self, points: Any) -> Any:
        """Whether points lie in the free space (inside the boundary, outside holes).

        Examples
        --------
        >>> World([[0, 0], [4, 0], [4, 4], [0, 4]]).contains([[1, 1], [5, 1]]).tolist()
        [True, False]
        """
        p = np.asarray(points, dtype=np.float64)
        return shapely.contains_xy(self.polygon, p[..., 0], p[..., 1])

    def clearance(self, points: Any) -> Any:
        """Distance from points to the nearest wall (boundary or hole edge)."""
        return clearance(points, self.segments)

    def replace(self, **changes: Any) -> World:
        """A copy with some fields changed (the world itself never changes).

        Examples
        --------
        >>> World([[0, 0], [4, 0], [4, 4], [0, 4]]).replace(name="box").name
        'box'
        """
        return dataclasses.replace(self, **changes)

    # -- comparison and serialisation ----------------------------------------------

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, World):
            return NotImplemented
        return (
            self.name == other.name
            and np.array_equal(self.boundary, other.boundary)
            and len(self.holes) == len(other.holes)
            and all(np.array_equal(a, b) for a, b in zip(self.holes, other.holes, strict=True))
            and _opt_equal(self.start, other.start)
            and _opt_equal(self.goal, other.goal)
            and self.obstacles == other.obstacles
        )

    __hash__ = None  # type: ignore[assignment]

    def to_dict(self) -> dict[str, Any]:
        """The JSON form of docs/design.md ("World file")."""
        out: dict[str, Any] = {
            "name": self.name,
            "boundary": self.boundary.tolist(),
            "holes": [h.tolist() for h in self.holes],
        }
        if self.start is not None:
            out["start"] = self.start.tolist()
        if self.goal is not None:
            out["goal"] = self.goal.tolist()
        if self.obstacles is not None:
            out["obstacles"] = self.obstacles.to_dict()
        return out

    @classmethod
    def from_dict(cls, data: Any) -> World:
        """From the JSON form; unknown keys and wrong types are refused.

        Every error names the world and carries the JSON path of the offending part."""
        if not isinstance(data, dict):
            raise InvalidWorldError(f"a world must be a JSON object; got {_json_type(data)}")
        name = data.get("name", "world")
        try:
            return cls._from_dict(data)
        except InvalidWorldError as exc:
            if str(exc).startswith("world "):
                raise
            raise InvalidWorldError(f"world {name!r}: {exc}", where=exc.where) from None

    @classmethod
    def _from_dict(cls, data: dict[str, Any]) -> World:
        allowed = {"name", "boundary", "holes", "start", "goal", "obstacles"}
        unknown = sorted(set(data) - allowed)
        if unknown:
            raise InvalidWorldError(
                f"unknown keys {unknown}; expected some of {sorted(allowed)}", where=(unknown[0],)
            )
        if "boundary" not in data:
            raise InvalidWorldError("missing key 'boundary' (a list of [x, y] vertices)")
        holes = data.get("holes", [])
        if not isinstance(holes, list):
            raise InvalidWorldError(
                f"holes must be a list of polygons; got {_json_type(holes)}", where=("holes",)
            )
        obstacles = data.get("obstacles")
        with _at("obstacles"):
            spec = ObstacleSpec.from_dict(obstacles) if obstacles is not None else None
        return cls(
            boundary=_coords(data["boundary"], "boundary"),
            holes=tuple(_coords(h, "holes", k) for k, h in enumerate(holes)),
            name=data.get("name", "world"),
            start=_coords(data["start"], "start") if data.get("start") is not None else None,
            goal=_coords(data["goal"], "goal") if data.get("goal") is not None else None,
            obstacles=spec,
        )


def _simple_ring(coords: Any, name: str) -> FloatArray:
    """The ring as given (vertex numbers in messages are the user's), checked simple."""
    ring = as_ring(coords, name)
    big = float(np.abs(ring).max())
    if big > MAX_COORDINATE:
        raise InvalidWorldError(
            f"coordinates must be within +-{MAX_COORDINATE:,.0f} agent steps; the {name} "
            f"reaches {big:.3g}"
        )
    v = ring - ring[0]
    d = v[int(np.argmax(np.hypot(v[:, 0], v[:, 1])))]
    if np.all(np.abs(v[:, 0] * d[1] - v[:, 1] * d[0]) <= 1e-12 * float(d @ d)):
        raise InvalidWorldError(f"{name} must enclose an area; its vertices are collinear")
    # Shapely answers "simple?" in O(n log n); the pairwise search that names the crossing
    # edges runs only for a ring already known to be bad.
    crossings = [] if shapely.is_simple(LinearRing(ring)) else ring_crossings(ring)
    if crossings:
        i, j, (x, y) = crossings[0]
        raise InvalidWorldError(
            f"{name} must be a simple polygon; edges {i} and {j} cross at ({x:.6g}, {y:.6g})"
        )
    return ring


def _invalid_message(outer: Polygon, holes: list[Polygon], polygon: Polygon) -> InvalidWorldError:
    """Why boundary and holes do not make a valid polygon, in the world's terms."""
    for k, hp in enumerate(holes):
        shared = hp.boundary.intersection(outer.boundary)
        if shared.length > 0:
            p = shared.representative_point()
            return InvalidWorldError(
                f"hole {k} shares an edge with the boundary near ({p.x:.6g}, {p.y:.6g}); a "
                "hole must lie inside the boundary, touching it at single points at most "
                "(make such an obstacle part of the boundary instead)",
                where=("holes", k),
            )
    reason = shapely.is_valid_reason(polygon)
    return InvalidWorldError(
        f"boundary and holes do not bound one valid region ({reason.split('[')[0].lower()} "
        f"at {reason[reason.find('[') :] if '[' in reason else 'an unknown place'})"
    )


def _outside_message(k: int, hole: FloatArray, outer: Polygon) -> str:
    inside = shapely.contains_xy(outer, hole[:, 0], hole[:, 1])
    if not inside.all():
        v = int(np.argmin(inside))
        x, y = hole[v]
        return (
            f"hole {k} must lie strictly inside the boundary; its vertex {v} "
            f"({x:.6g}, {y:.6g}) does not"
        )
    where = Polygon(hole).boundary.intersection(outer.boundary).representative_point()
    return (
        f"hole {k} must lie strictly inside the boundary; it meets the boundary at "
        f"({where.x:.6g}, {where.y:.6g})"
    )


def _coords(value: Any, key: str, index: int | None = None) -> Any:
    """Check the JSON shape of coordinates (numbers, not strings or objects)."""
    where: tuple[str | int, ...] = (key,) if index is None else (key, index)
    name = key if index is None else f"hole {index}"

    def numeric(v: Any) -> bool:
        if isinstance(v, list):
            return all(numeric(x) for x in v)
        return isinstance(v, int | float) and not isinstance(v, bool)

    if not isinstance(value, list) or not numeric(value):
        raise InvalidWorldError(
            f"{name} must be a list of numbers; got {_json_type(value)}", where=where
        )
    return value


def _json_type(value: Any) -> str:
    names = {dict: "an object", list: "a list", str: "a string", bool: "a boolean"}
    for t, n in names.items():
        if isinstance(value, t):
            return n
    if value is None:
        return "null"
    return "a number" if isinstance(value, int | float) else type(value).__name__


def _opt_equal(a: FloatArray | None, b: FloatArray | None) -> bool:
    if a is None or b is None:
        return a is None and b is None
    return bool(np.array_equal(a, b))
