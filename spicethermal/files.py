"""Atomic file writing: a reader never sees a half-written file."""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Any

from .errors import DataFormatError, where


@contextmanager
def atomic_open(path: str | os.PathLike, mode: str = "w", **kwargs) -> Iterator[IO]:
    """Open ``path`` for writing through a temporary file in the same directory.

    The temporary file replaces ``path`` only when the block ends without an exception;
    otherwise it is removed and ``path`` is left as it was.

    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "x.txt"
    >>> with atomic_open(p) as f:
    ...     _ = f.write("hello")
    >>> p.read_text()
    'hello'
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, mode, **kwargs) as handle:
            yield handle
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise


def atomic_write_text(path: str | os.PathLike, text: str) -> Path:
    """Write ``text`` to ``path`` atomically and return the path."""
    with atomic_open(path, "w", encoding="utf-8", newline="\n") as handle:
        handle.write(text)
    return Path(path)


def atomic_write_bytes(path: str | os.PathLike, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically and return the path."""
    with atomic_open(path, "wb") as handle:
        handle.write(data)
    return Path(path)


def read_json(path: str | os.PathLike, missing: str = "no such file") -> Any:
    """Parse a JSON file; a missing or malformed file is a one-line :class:`DataFormatError`
    naming the file (and the line), ``missing`` saying what a missing file means."""
    path = Path(path)
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise DataFormatError(f"{path}: {missing}") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        line = getattr(exc, "lineno", None)
        raise DataFormatError(f"{where(path, line)}not valid JSON ({exc})") from None


def read_text(path: str | os.PathLike, label: object = None, kind: str = "text file") -> str:
    """Read a UTF-8 text file (a BOM is dropped); a missing, binary or directory path is a
    one-line :class:`DataFormatError` naming ``label`` (default the path) and ``kind``."""
    path = Path(path)
    name = label if label is not None else path
    try:
        return path.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise DataFormatError(f"{name}: file not found") from None
    except UnicodeDecodeError:
        raise DataFormatError(f"{name}: not a {kind} (UTF-8)") from None
    except IsADirectoryError:
        raise DataFormatError(f"{name}: is a directory, expected a {kind}") from None
