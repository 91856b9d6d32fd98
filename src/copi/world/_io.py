"""World files: JSON, one world or a list of them (docs/design.md, "World file")."""

from __future__ import annotations

import json
import os
from collections.abc import Iterable
from json.decoder import JSONArray, JSONObject  # type: ignore[attr-defined]
from json.scanner import py_make_scanner  # type: ignore[attr-defined]
from pathlib import Path
from typing import Any

from copi._files import atomic_write, regular_file
from copi.errors import CopiError, InvalidWorldError, WorldFileError
from copi.world._world import World

__all__ = ["MAX_WORLD_FILE_BYTES", "MAX_WORLDS", "load_worlds", "save_worlds"]

MAX_WORLD_FILE_BYTES = 32 * 1024 * 1024
"""World files larger than this (32 MiB) are refused before they are read."""
MAX_WORLDS = 20_000
"""World files with more worlds than this are refused before any world is built."""


def load_worlds(
    path: str | os.PathLike[str],
    *,
    max_bytes: int = MAX_WORLD_FILE_BYTES,
    max_worlds: int = MAX_WORLDS,
) -> list[World]:
    """Read a world file: one world object or a list of them (at most ``max_worlds``, in
    at most ``max_bytes`` of UTF-8, a byte-order mark allowed).

    Raises
    ------
    WorldFileError
        ``path:line:column: what was expected, what was found`` for a file that is
        missing, not JSON, or not in the world format (the place of the offending world
        or key is given when it can be found).

    Examples
    --------
    >>> import tempfile, os
    >>> d = tempfile.mkdtemp()
    >>> save_worlds([World([[0, 0], [4, 0], [4, 4]], name="tri")], os.path.join(d, "w.json"))
    >>> [w.name for w in load_worlds(os.path.join(d, "w.json"))]
    ['tri']
    """
    p = regular_file(path, "world file", WorldFileError)
    try:
        size = p.stat().st_size
        if size > max_bytes and p.is_file():
            raise WorldFileError(
                f"{p}: {size:,} bytes, more than a world file may hold ({max_bytes:,}); "
                "split it into several files"
            )
        text = p.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise WorldFileError(f"{p}: no such world file") from None
    except IsADirectoryError:
        raise WorldFileError(f"{p}: is a directory, expected a JSON world file") from None
    except UnicodeDecodeError:
        raise WorldFileError(f"{p}: not a text file; expected JSON (UTF-8)") from None
    except OSError as exc:
        raise WorldFileError(f"{p}: cannot read ({exc.strerror})") from None
    try:
        data, starts = _parse_with_positions(text)
    except json.JSONDecodeError as exc:
        hint = ""
        if p.suffix.lower() == ".map" or text.lstrip().startswith("type "):
            hint = (f"; it looks like a Moving AI map: make a world file of it with copi "
                    f"world import-movingai {p} -o {p.with_suffix('.json').name}")  # fmt: skip
        raise WorldFileError(
            f"{p}:{exc.lineno}:{exc.colno}: not valid JSON ({exc.msg}){hint}"
        ) from None
    except RecursionError:
        raise WorldFileError(f"{p}: JSON nested too deeply to be a world file") from None
    except ValueError as exc:  # a number of thousands of digits, beyond Python's int limit
        raise WorldFileError(f"{p}: not a world file ({str(exc).splitlines()[0]})") from None
    items = data if isinstance(data, list) else [data]
    if len(items) > max_worlds:
        raise WorldFileError(
            f"{p}: {len(items):,} worlds, more than a world file may hold ({max_worlds:,}); "
            "split it into several files"
        )
    if isinstance(data, list) and not data:
        raise WorldFileError(f"{p}:1:1: expected a world object or a non-empty list; got []")
    worlds = []
    for k, item in enumerate(items):
        node = starts.child(k) if isinstance(data, list) else starts
        try:
            worlds.append(World.from_dict(item))
        except CopiError as exc:
            where = exc.where if isinstance(exc, InvalidWorldError) else ()
            line, col = _line_col(text, node.find(where).start)
            label = f"world {k}: " if isinstance(data, list) and "world '" not in str(exc) else ""
            raise WorldFileError(f"{p}:{line}:{col}: {label}{exc}") from None
    return worlds


def save_worlds(worlds: World | Iterable[World], path: str | os.PathLike[str]) -> None:
    """Write worlds as a JSON list, atomically: an existing file is replaced only once the
    new one is complete, so an interruption never leaves half a file."""
    items = [worlds] if isinstance(worlds, World) else list(worlds)
    for w in items:
        if not isinstance(w, World):
            raise WorldFileError(f"save_worlds takes World objects; got {type(w).__name__}")
    p = Path(path)
    if p.parent and not p.parent.exists():
        raise WorldFileError(f"{p}: directory {p.parent} does not exist")
    text = _compact([w.to_dict() for w in items]) + "\n"
    atomic_write(p, lambda fh: fh.write(text.encode("utf-8")), "json")


def _compact(value: Any, depth: int = 0, width: int = 96) -> str:
    """JSON for people: objects a key per line, a list of numbers on one line, a list of
    points as many points per line as fit in ``width`` (not one number per line)."""
    pad = " " * (depth + 1)
    if isinstance(value, dict):
        if not value:
            return "{}"
        body = ",\n".join(
            f"{pad}{json.dumps(k)}: {_compact(v, depth + 1, width)}" for k, v in value.items()
        )
        return "{\n" + body + "\n" + " " * depth + "}"
    if isinstance(value, list) and value and not all(_flat(v) for v in value):
        body = ",\n".join(pad + _compact(v, depth + 1, width) for v in value)
        return "[\n" + body + "\n" + " " * depth + "]"
    if isinstance(value, list) and value and all(isinstance(v, list) for v in value):
        parts = [json.dumps(v, separators=(", ", ": ")) for v in value]
        lines, line = [], ""
        for part in parts:
            if line and len(pad) + len(line) + len(part) + 2 > width:
                lines.append(line + ",")
                line = ""
            line = f"{line}, {part}" if line else part
        lines.append(line)
        if len(lines) == 1:
            return f"[{lines[0]}]"
        return "[\n" + "\n".join(pad + ln for ln in lines) + "\n" + " " * depth + "]"
    return json.dumps(value, separators=(", ", ": "))


def _flat(v: Any) -> bool:
    """A number, a string, or a list of numbers (a point): what fits on a line."""
    if isinstance(v, list):
        return all(isinstance(x, int | float) and not isinstance(x, bool) for x in v)
    return not isinstance(v, dict)


class _Node:
    """Where a JSON value starts in the text, and where its children start."""

    __slots__ = ("start", "children")

    def __init__(self, start: int) -> None:
        self.start = start
        self.children: list[tuple[Any, _Node]] = []

    def child(self, key: Any) -> _Node:
        for k, node in self.children:
            if k == key:
                return node
        return self

    def find(self, where: tuple[str | int, ...]) -> _Node:
        """The deepest node along the JSON path ``where`` that exists."""
        node = self
        for key in where:
            nxt = node.child(key)
            if nxt is node:
                break
            node = nxt
        return node


def _parse_with_positions(text: str) -> tuple[Any, _Node]:
    """json.loads that also returns the start offset of every value (for error lines).

    The stock decoder keeps no positions; its pure-Python scanner calls hooks for objects
    and arrays, which are wrapped here to record each member's offset."""
    decoder = json.JSONDecoder()
    stack: list[_Node] = []

    def recording(scan_once: Any, node: _Node, is_object: bool) -> Any:
        def scan(s: str, idx: int) -> Any:
            child = _Node(idx)
            key = _key_before(s, idx) if is_object else len(node.children)
            node.children.append((key, child))
            stack.append(child)
            try:
                return scan_once(s, idx)
            finally:
                stack.pop()

        return scan

    def parse_object(s_and_end: Any, strict: bool, scan_once: Any, *rest: Any) -> Any:
        return JSONObject(s_and_end, strict, recording(scan_once, stack[-1], True), *rest)

    def parse_array(s_and_end: Any, scan_once: Any) -> Any:
        return JSONArray(s_and_end, recording(scan_once, stack[-1], False))

    decoder.parse_object = parse_object  # type: ignore[attr-defined]
    decoder.parse_array = parse_array  # type: ignore[attr-defined]
    decoder.scan_once = py_make_scanner(decoder)  # type: ignore[attr-defined]
    start = len(text) - len(text.lstrip())
    root = _Node(start)
    stack.append(root)
    data = decoder.decode(text)
    return data, root


def _key_before(s: str, idx: int) -> str:
    """The key of the object member whose value starts at ``idx``: the string before the
    colon before it."""
    close = s.rfind('"', 0, s.rfind(":", 0, idx))
    open_ = close - 1
    while open_ >= 0 and not (s[open_] == '"' and s[open_ - 1] != "\\"):
        open_ -= 1
    try:
        return str(json.loads(s[open_ : close + 1]))
    except json.JSONDecodeError:  # pragma: no cover - the decoder already accepted it
        return ""


def _line_col(text: str, offset: int) -> tuple[int, int]:
    line = text.count("\n", 0, offset) + 1
    col = offset - (text.rfind("\n", 0, offset) + 1) + 1
    return line, col
