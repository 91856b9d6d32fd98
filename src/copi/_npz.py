"""The one reader of copi's ``.npz`` files (capabilities, causal maps, policy weights).

Every such file is a zip of ``.npy`` members plus a ``metadata`` member holding JSON
(format name and version). :func:`read_npz` reads only the members a format knows, each
refused *before* it is unpacked when it would be larger than the format allows (a small
file may hold a member of gigabytes of zeros), never unpickles anything, and turns every
way a file can be broken (missing, a directory, truncated, not a zip, another
compression, encrypted, object arrays) into one error of the format's own class naming
the file. :func:`read_metadata` then checks the format's name and version.
"""

from __future__ import annotations

import json
import os
import zipfile
import zlib
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi._files import regular_file
from copi.errors import CopiError

__all__ = ["read_metadata", "read_npz"]


def read_npz(
    path: str | os.PathLike[str],
    members: Iterable[str],
    *,
    error: type[CopiError],
    what: str,
    max_member: int,
    max_total: int,
) -> dict[str, NDArray[Any]]:
    """The known ``members`` of the archive at ``path`` as arrays (absent ones left out).

    Raises ``error`` (one line starting with the path) for a missing or unreadable file,
    one that is not a complete zip, a member that would unpack to more than
    ``max_member`` bytes (or all of them to more than ``max_total``), or a member that is
    not a plain array. ``what`` names the kind of file ("capabilities file").
    """
    p = regular_file(path, what, error)
    out: dict[str, NDArray[Any]] = {}
    total = 0
    try:
        with zipfile.ZipFile(p) as zf:
            infos = {i.filename: i for i in zf.infolist()}
            for name in members:
                info = infos.get(f"{name}.npy")
                if info is None:
                    continue
                total += info.file_size
                if info.file_size > max_member or total > max_total:
                    raise error(
                        f"{p}: member {name!r} unpacks to {info.file_size:,} bytes, more than "
                        f"a {what} holds (at most {max_member:,} per member, {max_total:,} in "
                        "all)"
                    )
                with zf.open(info) as fh:
                    out[name] = _array(fh, p, name, error, what, max_member)
    except (zipfile.BadZipFile, EOFError, zlib.error) as exc:
        raise error(f"{p}: not a complete .npz archive (truncated or corrupt: {exc})") from None
    except (NotImplementedError, RuntimeError) as exc:  # other compression, encryption
        raise error(f"{p}: not a copi {what} ({exc})") from None
    except OSError as exc:
        raise error(f"{p}: cannot read ({exc.strerror or exc})") from None
    return out


def _array(
    fh: Any, p: Path, name: str, error: type[CopiError], what: str, most: int
) -> NDArray[Any]:
    """One ``.npy`` member, its header read first: an array whose header claims more
    bytes than ``most`` (whatever the zip says of its size), or Python objects, is
    refused before anything is allocated."""
    try:
        version = np.lib.format.read_magic(fh)
        if version == (1, 0):
            shape, fortran, dtype = np.lib.format.read_array_header_1_0(fh)
        elif version == (2, 0):
            shape, fortran, dtype = np.lib.format.read_array_header_2_0(fh)
        else:
            raise ValueError(f"npy format version {version}")
    except ValueError as exc:
        raise error(f"{p}: member {name!r} is not an array ({str(exc).splitlines()[0]})") from None
    if dtype.hasobject:
        raise error(f"{p}: member {name!r} holds Python objects, which copi never loads")
    if dtype.itemsize == 0 or dtype.kind not in "biufcSU":
        raise error(f"{p}: member {name!r} holds {dtype} items; a copi {what} holds "
                    "numbers and text only")  # fmt: skip
    if any(int(d) < 0 for d in shape) or len(shape) > 8:
        raise error(f"{p}: member {name!r} has shape {shape}; expected at most 8 sizes, "
                    "each >= 0")  # fmt: skip
    count = 1
    for d in shape:
        count *= int(d)
    size = count * dtype.itemsize
    if size > most:
        raise error(
            f"{p}: member {name!r} claims {size:,} bytes ({'x'.join(map(str, shape)) or 1} "
            f"{dtype}), more than a {what} holds (at most {most:,})"
        )
    data = fh.read(size)
    if len(data) != size:
        raise error(f"{p}: member {name!r} is cut short ({len(data):,} of {size:,} bytes)")
    arr = np.frombuffer(data, dtype=dtype, count=count)
    return arr.reshape(shape, order="F" if fortran else "C").copy()


def read_metadata(
    arrays: dict[str, NDArray[Any]],
    path: str | os.PathLike[str],
    *,
    fmt: str,
    version: int,
    error: type[CopiError],
    what: str,
) -> dict[str, Any]:
    """The JSON ``metadata`` member of a file read by :func:`read_npz`, checked to be of
    format ``fmt`` and a version this copi reads (at most ``version``)."""
    p = Path(path)
    if "metadata" not in arrays:
        raise error(f"{p}: not a copi {what} (no metadata entry)")
    try:
        meta = json.loads(str(arrays["metadata"][()]))
    except (json.JSONDecodeError, TypeError, IndexError, ValueError) as exc:
        raise error(f"{p}: metadata is not JSON ({exc})") from None
    found = meta.get("format") if isinstance(meta, dict) else None
    if found != fmt:
        raise error(f"{p}: not a copi {what} (format {found!r})")
    v = meta.get("version")
    if not isinstance(v, int) or isinstance(v, bool) or v < 1:
        raise error(f"{p}: bad format version {v!r}")
    if v > version:
        raise error(
            f"{p}: written by a newer copi (format version {v}); this copi reads versions up "
            f"to {version}: upgrade copi"
        )
    return meta
