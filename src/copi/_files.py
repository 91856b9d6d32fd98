"""Writing user files safely: one rule for every file copi writes for a user.

- **Atomic**: a file is written beside its target under a temporary name and renamed
  over it only once complete (:func:`atomic_path`, :func:`atomic_write`), so a full
  disk, a crash or Ctrl-C never leaves half a file in place of the old one, and an
  error names the user's file, not the temporary one.
- **Never over another kind of file**: before anything is written, every output path is
  checked (:func:`check_outputs`): it may not be one of the command's inputs, two
  outputs may not be one file, and an existing file is replaced only by a file of its
  own kind (a report never replaces a results store, capabilities never replace a
  figure).
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import stat
import tempfile
import zipfile
from collections.abc import Callable, Iterable, Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Any

import numpy as np

from copi.errors import InvalidArgumentError

__all__ = [
    "atomic_path",
    "check_writable",
    "regular_file",
    "atomic_write",
    "check_outputs",
    "file_kind",
    "file_sha",
    "save_figure",
    "write_npz",
    "write_text",
]

# What an output of each kind may replace (by the existing file's content, see file_kind)
_NPZ_FORMATS = {"copi-capabilities": "capabilities file", "copi-policy": "policy file",
                "copi-causal-map": "causal map", "copi-sarl": "SARL network"}
"""What a copi ``.npz`` holds, by the format its metadata names."""

_KINDS = {
    "results": {"results store"},
    "npz": {"npz archive", *_NPZ_FORMATS.values()},
    "capabilities": {"npz archive", "capabilities file"},
    "policy": {"npz archive", "policy file"},
    "SARL network": {"npz archive", "SARL network"},
    "causal map": {"npz archive", "causal map"},
    "png": {"PNG image"},
    "gif": {"GIF image"},
    "mp4": {"MP4 video"},
    "json": {"JSON", "text"},
    "text": {"text"},
    "directory": {"directory"},
}


def _npz_format(path: Path) -> str | None:
    """The format a copi ``.npz``'s metadata names, or None (another archive, or one that
    cannot be read: what it holds is then told by its first bytes only)."""
    try:
        with zipfile.ZipFile(path) as zf:
            info = zf.getinfo("metadata.npy")
            if info.file_size > 1 << 20:  # a copi file's metadata is a few kilobytes
                return None
            with zf.open(info) as fh:
                meta = np.lib.format.read_array(fh, allow_pickle=False)
        found = json.loads(str(meta[()])).get("format")
    except Exception:  # anything unreadable is simply not a copi file
        return None
    return found if isinstance(found, str) else None


def file_kind(path: str | os.PathLike[str]) -> str | None:
    """What an existing file holds, from its first bytes: "results store" (SQLite),
    "npz archive" (zip), "PNG image", "GIF image", "MP4 video", "JSON", "text", or
    "binary data"; None for a missing or empty file.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "a.md"
    >>> _ = p.write_text("# a report")
    >>> file_kind(p), file_kind(p.with_name("missing"))
    ('text', None)
    """
    p = Path(path)
    try:
        st = p.stat()
    except FileNotFoundError:
        return None
    except NotADirectoryError:
        return "path below a file"
    except OSError:
        return "unreadable file"
    if stat.S_ISDIR(st.st_mode):
        return "directory"
    if not stat.S_ISREG(st.st_mode):  # opening a FIFO would wait for a writer
        return "device, pipe or socket"
    try:
        with open(p, "rb") as fh:
            head = fh.read(512)
    except FileNotFoundError:
        return None
    except IsADirectoryError:
        return "directory"
    except NotADirectoryError:
        return "path below a file"
    except OSError:
        return "unreadable file"
    if not head:
        return None
    if head.startswith(b"SQLite format 3\x00"):
        return "results store"
    if head.startswith(b"PK\x03\x04") or head.startswith(b"PK\x05\x06"):
        return _NPZ_FORMATS.get(_npz_format(p) or "", "npz archive")
    if head.startswith(b"\x89PNG"):
        return "PNG image"
    if head.startswith(b"GIF8"):
        return "GIF image"
    if head[4:8] == b"ftyp":
        return "MP4 video"
    try:
        text = head.decode("utf-8")
    except UnicodeDecodeError:
        # a multi-byte character cut by the 512-byte window is still text
        try:
            text = head[:-3].decode("utf-8")
        except UnicodeDecodeError:
            return "binary data"
    if "\x00" in text:
        return "binary data"
    return "JSON" if text.lstrip()[:1] in ("{", "[") else "text"


def _same(a: Path, b: Path) -> bool:
    try:
        if a.exists() and b.exists():
            return a.samefile(b)
    except OSError:
        pass
    return a.resolve() == b.resolve()


def check_outputs(
    outputs: Mapping[str, tuple[str | os.PathLike[str], str]],
    inputs: Iterable[str | os.PathLike[str] | None] = (),
) -> None:
    """Refuse, before anything is written, outputs that would destroy something.

    ``outputs`` maps a label (what the file is, e.g. "the report") to (path, kind), kind
    one of "results", "npz", "png", "gif", "mp4", "json", "text" or "directory" (a
    directory to write into). Refused, in one line
    naming the file: an output that is one of ``inputs``; two outputs that are one file;
    an output that is a directory; an existing file of another kind than the output's
    (e.g. a report over a results store). An existing file of the same kind is replaced
    (atomically) when written.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> try:
    ...     check_outputs({"the store": (d / "r.md", "results"),
    ...                    "the report": (d / "r.md", "text")})
    ... except InvalidArgumentError as err:
    ...     print(str(err).replace(str(d), "D"))
    D/r.md would be both the store and the report; name the output differently
    """
    given = [Path(p) for p in inputs if p is not None]
    seen: list[tuple[str, Path]] = []
    for label, (raw, kind) in outputs.items():
        path = Path(raw)
        for inp in given:
            if _same(path, inp):
                raise InvalidArgumentError(
                    f"{path} is an input of this command; writing {label} there would "
                    "replace it: choose another output"
                )
        for other_label, other in seen:
            if _same(path, other):
                raise InvalidArgumentError(
                    f"{path} would be both {other_label} and {label}; name the output "
                    "differently"
                )
        seen.append((label, path))
        for parent in path.parents:
            if parent.exists() and not parent.is_dir():
                raise InvalidArgumentError(
                    f"{parent} is a file, not a directory; {label} cannot be written in it"
                )
        found = file_kind(path)
        if kind == "directory":
            if found is None and path.exists():  # an empty file is still not a directory
                found = "empty file"
            if found not in (None, "directory"):
                raise InvalidArgumentError(
                    f"{path} exists and is not a directory; expected a directory for {label}"
                )
            continue
        if found == "directory":
            raise InvalidArgumentError(f"{path} is a directory; expected a file for {label}")
        if found is not None and found not in _KINDS[kind]:
            article = "an" if found[0] in "aeiou" else "a"
            raise InvalidArgumentError(
                f"{path} exists and holds {article} {found}; writing {label} there would "
                "replace it: choose another output (or move that file away)"
            )


def _check_replaceable(target: Path, kind: str | None) -> None:
    if kind is not None:
        check_outputs({f"a {kind} file": (target, kind)})


@contextmanager
def atomic_path(path: str | os.PathLike[str], kind: str | None = None) -> Iterator[Path]:
    """A temporary path beside ``path`` (same suffix) to write the whole file to; renamed
    over ``path`` when the block ends without error, removed otherwise. For writers that
    want a file name (matplotlib, Pillow, ffmpeg). The file gets the usual permissions
    (0666 less umask); an OSError names ``path``. With ``kind`` (see
    :func:`check_outputs`), an existing file of another kind is refused first."""
    target = Path(path)
    _check_replaceable(target, kind)
    directory = target.parent if str(target.parent) else Path(".")
    try:
        fd, tmp = tempfile.mkstemp(
            prefix=f".{target.stem}.", suffix=f".tmp{target.suffix}", dir=directory
        )
        os.close(fd)
    except OSError as exc:
        raise _about(exc, target) from None
    try:
        yield Path(tmp)
        mask = os.umask(0)
        os.umask(mask)
        os.chmod(tmp, 0o666 & ~mask)
        os.replace(tmp, target)
    except OSError as exc:
        Path(tmp).unlink(missing_ok=True)
        raise _about(exc, target) from None
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def atomic_write(
    path: str | os.PathLike[str],
    write: Callable[[IO[bytes]], object],
    kind: str | None = None,
) -> Path:
    """Write ``path`` through ``write(fh)`` (see :func:`atomic_path`): an existing file is
    replaced only once the new one is complete, so an interruption never leaves half a
    file."""
    with atomic_path(path, kind) as tmp, open(tmp, "wb") as fh:
        write(fh)
    return Path(path)


def write_text(path: str | os.PathLike[str], text: str, kind: str = "text") -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically; ``kind`` ("text" or "json") is what
    it holds, so that a file of another kind there is refused (:func:`check_outputs`)."""
    data = text.encode("utf-8")
    return atomic_write(path, lambda fh: fh.write(data), kind)


def save_figure(fig: Any, path: str | os.PathLike[str], **kwargs: Any) -> Path:
    """``fig.savefig`` to ``path`` atomically (rendered in memory first, in the format
    ``path``'s suffix names)."""
    buf = io.BytesIO()
    fmt = Path(path).suffix.lstrip(".").lower() or "png"
    fig.savefig(buf, format=fmt, **kwargs)
    data = buf.getvalue()
    return atomic_write(path, lambda fh: fh.write(data), fmt if fmt in _KINDS else None)


def _about(exc: OSError, target: Path) -> OSError:
    """The error as about the user's file, not the temporary one beside it (same errno,
    hence the same subclass: FileNotFoundError, IsADirectoryError, ...)."""
    if exc.errno is None:
        return exc
    return OSError(exc.errno, exc.strerror or str(exc), str(target))


def write_npz(
    path: str | os.PathLike[str], arrays: Mapping[str, Any], kind: str = "npz"
) -> Path:
    """Write ``arrays`` as an ``.npz`` (no pickle), atomically (:func:`atomic_write`),
    byte for byte the same for the same arrays: fixed member order and zip timestamps,
    so that a file's hash names its content. ``kind`` ("capabilities", "policy", "causal
    map"): what it holds, so that a copi file of another kind there is refused."""

    def write(fh: IO[bytes]) -> None:
        with zipfile.ZipFile(fh, "w", compression=zipfile.ZIP_DEFLATED) as zf:
            for name, arr in arrays.items():
                info = zipfile.ZipInfo(f"{name}.npy", date_time=(1980, 1, 1, 0, 0, 0))
                info.compress_type = zipfile.ZIP_DEFLATED
                info.external_attr = 0o644 << 16
                with zf.open(info, "w", force_zip64=True) as member:
                    np.lib.format.write_array(member, np.asarray(arr), allow_pickle=False)

    return atomic_write(path, write, kind)


def file_sha(path: str | os.PathLike[str]) -> str:
    """The SHA-256 of a file's content (read in blocks)."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def regular_file(path: str | os.PathLike[str], what: str, error: type[Exception]) -> Path:
    """``path`` if it names a regular file; otherwise one ``error`` saying what it is
    (missing, a directory, or a device, pipe or socket, which would be read forever or
    block: ``/dev/zero``, a FIFO)."""
    p = Path(path)
    try:
        st = p.stat()
    except FileNotFoundError:
        raise error(f"{p}: no such {what}") from None
    except OSError as exc:
        raise error(f"{p}: cannot read ({exc.strerror or exc})") from None
    if stat.S_ISDIR(st.st_mode):
        raise error(f"{p}: is a directory, expected a {what}")
    if not stat.S_ISREG(st.st_mode):
        raise error(f"{p}: not a regular file (a device, a pipe or a socket), expected a {what}")
    return p


def check_writable(directory: str | os.PathLike[str], label: str) -> None:
    """Refuse, before any work, a directory ``label`` cannot be written to (made if
    missing, then a file created and removed there), in one line naming it."""
    d = Path(directory) if str(directory) else Path(".")
    try:
        d.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(prefix=".copi-probe.", dir=d)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise InvalidArgumentError(
            f"{d}: cannot write {label} there ({exc.strerror or exc}); choose another place"
        ) from None
