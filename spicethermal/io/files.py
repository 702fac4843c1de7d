"""Files, read and written safely: the one place where spicethermal touches the disk.

* Writing is atomic: a reader sees the complete old or the complete new file, never half of
  one (:func:`atomic_open`); a directory is replaced the same way (:func:`replace_dir`). New
  files get the mode the umask allows (0644 under umask 022), as ``open`` would give them.
* Reading is confined and bounded: only regular files (no FIFO, no device), inside ``root``
  when one is given (a symbolic link that leads out of it is refused before anything is
  read), at most :data:`MAX_BYTES` bytes and :data:`MAX_ROWS` lines; errors name the file and
  the limit, never the content of a file outside ``root``.
* JSON is strict both ways: :func:`read_json` refuses non-finite numbers and absurd nesting,
  :func:`dumps_json` turns non-finite numbers into ``null`` and says why.
* :func:`locked` is an advisory lock for a directory that one writer at a time may change.
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import fcntl
import json
import math
import os
import re
import shutil
import stat
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Any

from ..core.errors import BusyError, DataFormatError, where

#: Largest file read (bytes): far above any measurement, far below the memory of a laptop.
MAX_BYTES = 256 * 1024 * 1024
#: Most lines in a text file (a 10^6-row curve fits five times over).
MAX_ROWS = 5_000_000
#: Deepest nesting accepted in a JSON file (a model or manifest needs 4).
MAX_JSON_DEPTH = 64


def umask() -> int:
    """The process's umask (read without changing it where the system allows)."""
    with contextlib.suppress(OSError):
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("Umask:"):
                return int(line.split()[1], 8)
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def fsync_dir(path: str | os.PathLike) -> None:
    """Make a rename or a new entry in directory ``path`` durable (no-op where unsupported)."""
    with contextlib.suppress(OSError):
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


# -------------------------------------------------------------------------------- writing
@contextmanager
def atomic_open(path: str | os.PathLike, mode: str = "w", **kwargs) -> Iterator[IO]:
    """Open ``path`` for writing through a temporary file in the same directory.

    The temporary file (flushed and fsynced) replaces ``path`` only when the block ends
    without an exception; otherwise it is removed and ``path`` is left as it was. The file
    gets mode ``0666 & ~umask``.

    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "x.txt"
    >>> with atomic_open(p) as f:
    ...     _ = f.write("hello")
    >>> p.read_text(), oct(p.stat().st_mode & 0o777) == oct(0o666 & ~umask())
    ('hello', True)
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        os.fchmod(fd, 0o666 & ~umask())
        with os.fdopen(fd, mode, **kwargs) as handle:
            yield handle
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, path)
        fsync_dir(path.parent)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def atomic_write_text(path: str | os.PathLike, text: str) -> Path:
    """Write ``text`` to ``path`` atomically (UTF-8, ``\\n`` line ends) and return the path."""
    with atomic_open(path, "w", encoding="utf-8", newline="\n") as handle:
        handle.write(text)
    return Path(path)


def atomic_write_bytes(path: str | os.PathLike, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically and return the path."""
    with atomic_open(path, "wb") as handle:
        handle.write(data)
    return Path(path)


def write_json(path: str | os.PathLike, obj: Any) -> Path:
    """Write ``obj`` as strict JSON (:func:`dumps_json`, indented) to ``path`` atomically."""
    return atomic_write_text(path, dumps_json(obj, indent=2) + "\n")


def _renameat2_exchange(src: str, dst: str) -> bool:
    """Swap two paths atomically (Linux renameat2 RENAME_EXCHANGE); False if unsupported."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        fn = libc.renameat2
    except (OSError, AttributeError):
        return False
    at_fdcwd, rename_exchange = -100, 2
    if fn(at_fdcwd, os.fsencode(src), at_fdcwd, os.fsencode(dst), rename_exchange) == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.EINVAL, errno.ENOSYS, errno.ENOTSUP, errno.EPERM):
        return False
    raise OSError(err, os.strerror(err), dst)


def temp_dir_for(path: str | os.PathLike, suffix: str = ".tmp") -> Path:
    """A new empty directory beside ``path`` (hidden, named after it; mode from the umask),
    the place to build a replacement for :func:`replace_dir`."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{path.name}.", suffix=suffix, dir=path.parent))
    os.chmod(tmp, 0o777 & ~umask())
    return tmp


def replace_dir(new: str | os.PathLike, path: str | os.PathLike) -> None:
    """Put the complete directory ``new`` at ``path``; at every instant ``path`` holds the
    complete old or the complete new directory.

    On Linux the two are swapped in one step (``renameat2(RENAME_EXCHANGE)``) and the old one
    is removed afterwards. Elsewhere the old one is renamed to ``.NAME.*.old`` first and
    :func:`clean_leftovers` puts it back if the process dies before the second rename.

    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> (d / "b").mkdir(); _ = (d / "b" / "v").write_text("old")
    >>> new = temp_dir_for(d / "b"); _ = (new / "v").write_text("new")
    >>> replace_dir(new, d / "b"); (d / "b" / "v").read_text(), sorted(os.listdir(d))
    ('new', ['b'])
    """
    new, path = Path(new), Path(path)
    fsync_dir(new)
    if not path.exists():
        os.rename(new, path)
    elif _renameat2_exchange(str(new), str(path)):
        fsync_dir(path.parent)
        shutil.rmtree(new, ignore_errors=True)
        return
    else:  # pragma: no cover - systems without an atomic exchange
        old = Path(tempfile.mkdtemp(prefix=f".{path.name}.", suffix=".old", dir=path.parent))
        os.rename(path, old / "dir")
        os.rename(new, path)
        shutil.rmtree(old, ignore_errors=True)
    fsync_dir(path.parent)


def clean_leftovers(path: str | os.PathLike) -> list[Path]:
    """Remove what an interrupted :func:`replace_dir` or :func:`temp_dir_for` left beside
    ``path`` (restoring the old directory first if ``path`` itself went missing); returns
    the paths removed. Call it only while holding :func:`locked` for ``path``."""
    path = Path(path)
    removed: list[Path] = []
    if not path.parent.is_dir():
        return removed
    ours = re.compile(rf"\.{re.escape(path.name)}\.[a-z0-9_]{{8}}\.(tmp|old)")  # mkdtemp's
    for name in sorted(os.listdir(path.parent)):
        entry = path.parent / name
        if not ours.fullmatch(name) or not entry.is_dir() or entry.is_symlink():
            continue
        if entry.suffix == ".old" and not path.exists() and (entry / "dir").is_dir():
            os.rename(entry / "dir", path)  # pragma: no cover - fallback of replace_dir
        shutil.rmtree(entry, ignore_errors=True)
        removed.append(entry)
    return removed


def link_tree(src: str | os.PathLike, dst: str | os.PathLike, names: list[str]) -> None:
    """Put entries ``names`` of directory ``src`` into ``dst`` without copying data where
    possible: files as hard links (copied if linking fails), directories recursively,
    symbolic links as links (never followed)."""
    src, dst = Path(src), Path(dst)
    for name in names:
        s, d = src / name, dst / name
        if s.is_symlink():
            os.symlink(os.readlink(s), d)
        elif s.is_dir():
            d.mkdir()
            shutil.copymode(s, d)
            link_tree(s, d, sorted(os.listdir(s)))
        elif s.is_file():
            try:
                os.link(s, d)
            except OSError:
                shutil.copy2(s, d)


# -------------------------------------------------------------------------------- locking
_HELD: dict[str, tuple[int, int]] = {}  # lock file -> (fd, depth), for re-entry


def lock_path(path: str | os.PathLike) -> Path:
    """The lock file of directory ``path``: ``.NAME.lock`` beside it (beside, not inside, so
    that one lock guards every version of a directory that :func:`replace_dir` replaces)."""
    path = Path(os.path.realpath(path))  # one lock whatever link leads to the directory
    return path.parent / f".{path.name}.lock"


@contextmanager
def locked(path: str | os.PathLike, *, wait: bool = False) -> Iterator[Path]:
    """Hold the advisory lock of directory ``path`` (re-entrant within a process).

    The lock is ``flock`` on :func:`lock_path`, which exists only while held. Without
    ``wait``, a lock held by another process raises :class:`BusyError` at once, naming the
    process; with ``wait`` it blocks until the other writer is done (or dead: the kernel
    drops the lock of a killed process).

    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp()) / "b"
    >>> with locked(d), locked(d):
    ...     lock_path(d).exists()
    True
    >>> lock_path(d).exists()
    False
    """
    lock = lock_path(path)
    key = str(lock)
    if key in _HELD:
        fd, depth = _HELD[key]
        _HELD[key] = (fd, depth + 1)
        try:
            yield lock
        finally:
            _HELD[key] = (fd, depth)
        return
    lock.parent.mkdir(parents=True, exist_ok=True)
    while True:
        fd = os.open(lock, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o666 & ~umask())
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            if not wait:
                holder = os.pread(fd, 64, 0).decode("ascii", "replace").strip() or "?"
                os.close(fd)
                raise BusyError(f"{path}: another process (pid {holder}) is writing this "
                                f"bundle; try again when it is done, or wait for it with "
                                f"--wait") from None
            fcntl.flock(fd, fcntl.LOCK_EX)
        try:  # the holder before us may have removed the file: lock the current one
            same = os.stat(lock).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)
    try:
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        _HELD[key] = (fd, 1)
        try:
            yield lock
        finally:
            del _HELD[key]
            with contextlib.suppress(OSError):
                os.unlink(lock)  # while still held, so no one locks a removed file
    finally:
        os.close(fd)  # releases the lock


# -------------------------------------------------------------------------------- reading
def open_bounded(path: str | os.PathLike, label: object = None, *,
                 root: str | os.PathLike | None = None, max_bytes: int | None = None) -> bytes:
    """The bytes of regular file ``path``, confined and bounded.

    Parameters
    ----------
    path : the file.
    label : how messages name it (default: the path).
    root : when given, the file must lie inside this directory once every symbolic link is
        resolved; otherwise it is refused unread.
    max_bytes : size limit (default :data:`MAX_BYTES`).

    Returns
    -------
    bytes
        The content.

    Raises
    ------
    DataFormatError
        Missing, outside ``root``, not a regular file (FIFO, device, directory), too large,
        or a name with a NUL character; one line naming ``label`` and the limit.
    """
    limit = MAX_BYTES if max_bytes is None else max_bytes
    name = label if label is not None else path
    if "\0" in os.fspath(path):
        raise DataFormatError(f"{where(name)}the file name contains a NUL character")
    real = os.path.realpath(path)
    if root is not None:
        top = os.path.realpath(root)
        if os.path.commonpath([top, real]) != top:
            raise DataFormatError(f"{name}: leads outside the bundle (a symbolic link?); "
                                  f"only files inside the bundle are read")
    try:
        fd = os.open(real, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOFOLLOW", 0)
                     | os.O_CLOEXEC)
    except FileNotFoundError:
        raise DataFormatError(f"{name}: file not found") from None
    except OSError as exc:
        raise DataFormatError(f"{name}: cannot open ({exc.strerror})") from None
    info = os.fstat(fd)
    if not stat.S_ISREG(info.st_mode):
        os.close(fd)
        what = "is a directory" if stat.S_ISDIR(info.st_mode) else "not a regular file (a " \
            "pipe, socket or device)"
        raise DataFormatError(f"{name}: {what}, expected a file; not read")
    if info.st_size > limit:
        os.close(fd)
        raise DataFormatError(f"{name}: {info.st_size} bytes, above the limit of {limit} "
                              f"bytes (spicethermal.io.files.MAX_BYTES)")
    with os.fdopen(fd, "rb") as handle:
        data = handle.read(limit + 1)
    if len(data) > limit:
        raise DataFormatError(f"{name}: above the limit of {limit} bytes "
                              f"(spicethermal.io.files.MAX_BYTES)")
    return data


def read_text(path: str | os.PathLike, label: object = None, kind: str = "text file", *,
              root: str | os.PathLike | None = None, max_rows: int | None = None) -> str:
    """Read a UTF-8 text file (a BOM is dropped) through :func:`open_bounded`; a missing,
    binary, hostile or oversized file is a one-line :class:`DataFormatError` naming ``label``
    (default the path) and ``kind``; more than ``max_rows`` lines (default :data:`MAX_ROWS`)
    too.

    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "a.csv"
    >>> _ = p.write_text("t_s\\n1\\n2\\n")
    >>> read_text(p).splitlines()
    ['t_s', '1', '2']
    >>> read_text(p, "a.csv", max_rows=2)
    Traceback (most recent call last):
    ...
    spicethermal.core.errors.DataFormatError: a.csv: more than 2 lines, the limit \
(spicethermal.io.files.MAX_ROWS)
    """
    name = label if label is not None else path
    data = open_bounded(path, name, root=root)
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise DataFormatError(f"{name}: not a {kind} (UTF-8)") from None
    limit = MAX_ROWS if max_rows is None else max_rows
    if text.count("\n") > limit:
        raise DataFormatError(f"{name}: more than {limit} lines, the limit "
                              f"(spicethermal.io.files.MAX_ROWS)")
    return text


def _finite(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f"the number {text[:40]} is out of range (not a finite double)")
    return value


def _no_constant(text: str) -> float:
    raise ValueError(f"{text} is not a number JSON allows")


def loads_json(text: str, label: object = "<json>") -> Any:
    """Parse strict JSON: no NaN/Infinity, no number out of double range (``1e400``), nesting
    at most :data:`MAX_JSON_DEPTH`; errors are one-line :class:`DataFormatError` s.

    >>> loads_json('{"a": [1, 2.5]}')
    {'a': [1, 2.5]}
    >>> loads_json('[1e400]', 'x.json')
    Traceback (most recent call last):
    ...
    spicethermal.core.errors.DataFormatError: x.json: not valid JSON (the number 1e400 is out of \
range (not a finite double))
    """
    depth = level = 0
    in_string = escaped = False
    for ch in text:  # nesting depth, found before the recursive parser can overflow
        if in_string:
            if escaped:
                escaped = False
            elif ch == "\\":
                escaped = True
            elif ch == '"':
                in_string = False
        elif ch == '"':
            in_string = True
        elif ch in "[{":
            level += 1
            depth = max(depth, level)
        elif ch in "]}":
            level -= 1
    if depth > MAX_JSON_DEPTH:
        raise DataFormatError(f"{label}: JSON nested {depth} levels deep, above the limit of "
                              f"{MAX_JSON_DEPTH}")
    try:
        return json.loads(text, parse_float=_finite, parse_int=int,
                          parse_constant=_no_constant)
    except json.JSONDecodeError as exc:
        raise DataFormatError(f"{where(label, exc.lineno)}not valid JSON ({exc.msg}, column "
                              f"{exc.colno})") from None
    except (ValueError, RecursionError) as exc:
        raise DataFormatError(f"{label}: not valid JSON ({exc})") from None


def read_json(path: str | os.PathLike, missing: str = "no such file", *,
              root: str | os.PathLike | None = None) -> Any:
    """Parse a JSON file strictly (:func:`loads_json`), confined and bounded as
    :func:`read_text`; a missing file is a one-line :class:`DataFormatError` naming the file,
    ``missing`` saying what a missing file means."""
    path = Path(path)
    try:
        text = read_text(path, path, "JSON file", root=root)
    except DataFormatError as exc:
        if str(exc) == f"{path}: file not found":
            raise DataFormatError(f"{path}: {missing}") from None
        raise
    return loads_json(text, path)


# -------------------------------------------------------------------------------- JSON out
def strict(obj: Any, at: str = "", reasons: dict[str, str] | None = None) -> Any:
    """``obj`` with every non-finite float replaced by ``None``; each replacement is recorded
    in ``reasons`` (path -> why). NumPy scalars and arrays become plain numbers and lists.

    >>> r = {}
    >>> strict({"rms_k": float("inf"), "x": [1.0, float("nan")]}, reasons=r), r
    ({'rms_k': None, 'x': [1.0, None]}, {'rms_k': 'inf', 'x[1]': 'nan'})
    """
    reasons = {} if reasons is None else reasons
    if isinstance(obj, dict):
        return {k: strict(v, f"{at}.{k}" if at else str(k), reasons) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [strict(v, f"{at}[{i}]", reasons) for i, v in enumerate(obj)]
    if hasattr(obj, "tolist") and callable(obj.tolist):  # numpy arrays and scalars
        return strict(obj.tolist(), at, reasons)
    if isinstance(obj, float) and not math.isfinite(obj):
        reasons[at] = "nan" if math.isnan(obj) else ("inf" if obj > 0 else "-inf")
        return None
    return obj


def dumps_json(obj: Any, **kwargs) -> str:
    """Strict JSON text: non-finite numbers become ``null`` and, for an object, a key
    ``"null_reasons"`` says which and why (``{"rms_k": "inf"}``); never NaN or Infinity.

    >>> dumps_json({"peak_k": float("nan"), "n": 2})
    '{"peak_k": null, "n": 2, "null_reasons": {"peak_k": "nan: not a finite number"}}'
    """
    reasons: dict[str, str] = {}
    clean = strict(obj, "", reasons)
    if reasons and isinstance(clean, dict):
        clean["null_reasons"] = {k: f"{v}: not a finite number" for k, v in reasons.items()}
    return json.dumps(clean, allow_nan=False, **kwargs)

