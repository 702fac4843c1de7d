"""Reading SPICE libraries as PSpice, LTspice and ngspice write them (``.lib``, ``.txt``,
``.mod``, ``.sub``, ``.cir``).

Text: UTF-8 (a BOM is dropped), UTF-16 with a BOM, else Latin-1 (vendors' degree signs);
any letter case; ``+`` continuation lines (also indented); comments in every dialect's
spelling (``*`` lines, ``;`` and ``//`` anywhere, ``$`` after a blank unless it starts a
PSpice node name such as ``$N_0001``, ngspice's ``.control`` blocks); ``.include``/``.inc``
and ``.lib FILE [SECTION]`` followed inside the library's folder (``.lib NAME`` ... ``.endl``
sections are all read); ``.end`` ends a file. Every file goes through
:func:`spicethermal.io.files.open_bounded` (regular files only, size limit, no link out of
the library's folder). A binary or empty file, and an encrypted one (LTspice ``* LTspice
Encrypted File`` or ``<Binary File>``, PSpice ``$CDNENCSTART``, HSPICE ``.prot``), is named
as such; a stray ``.ENDS`` and a missing last ``.ENDS`` are forgiven, as simulators do, and
noted.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path

from ..core.errors import DataFormatError
from .files import open_bounded

#: Deepest chain of ``.include``/``.lib`` files followed.
MAX_INCLUDE_DEPTH = 8
_ENCRYPTED = (re.compile(r"^\*\s*LTspice\s+Encrypted", re.I), re.compile(r"\$CDNENCSTART", re.I),
              re.compile(r"^\s*\.prot(ect)?\b", re.I), re.compile(r"^\s*\*\*\s*Begin:\s*$", re.I))
_HEX_LINE = re.compile(r"^\s*(?:[0-9A-F]{2}\s+){7,}[0-9A-F]{2}\s*$")
_DOLLAR = re.compile(r"(?:^|\s)\$(?![A-Za-z]_)")  # not PSpice's $N_0001, $G_VCC nodes


@dataclass(frozen=True)
class Line:
    """One logical line (continuations joined, comments removed): its file, the number of its
    first physical line, and its text."""

    file: str
    number: int
    text: str

    @property
    def where(self) -> str:
        """``file, line N``, as messages name it."""
        return f"{self.file}, line {self.number}"


@dataclass
class Subckt:
    """A subcircuit definition: name, pins, ``PARAMS:`` defaults (text), body lines, and the
    subcircuit it is written inside (None at the top level)."""

    name: str
    pins: tuple[str, ...]
    line: Line
    defaults: dict[str, str] = field(default_factory=dict)
    body: list[Line] = field(default_factory=list)
    parent: Subckt | None = None
    #: PSpice ``OPTIONAL:`` pins (lower case) and the node an instance that omits one uses
    optional: dict[str, str] = field(default_factory=dict)


@dataclass
class Library:
    """A SPICE library: its subcircuits (in file order), its global ``.param`` and ``.func``
    lines, where it is encrypted, and what could not be read."""

    source: str
    subckts: list[Subckt]
    params: list[Line]
    funcs: list[Line] = field(default_factory=list)
    encrypted: list[Line] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    def find(self, name: str, inside: Subckt | None = None) -> Subckt | None:
        """The subcircuit ``name`` (any case) seen from inside ``inside``: a definition nested
        in it (or its parents) first, then a top-level one; None when there is none."""
        key = name.lower()
        scope = inside
        while scope is not None:
            for s in self.subckts:
                if s.parent is scope and s.name.lower() == key:
                    return s
            scope = scope.parent
        return next((s for s in self.subckts if s.parent is None and s.name.lower() == key),
                    next((s for s in self.subckts if s.name.lower() == key), None))

    def get(self, name: str | None) -> Subckt:
        """The subcircuit called ``name`` (any case), or the only one when ``name`` is None; a
        one-line error otherwise (naming encryption when the file is encrypted)."""
        if not self.subckts and self.encrypted:
            raise DataFormatError(f"{self.encrypted[0].where}: the library is encrypted; an "
                                  "encrypted model cannot be read (ask the vendor for the thermal "
                                  "network, or a datasheet Foster table)")
        if name is None:
            if len(self.subckts) == 1:
                return self.subckts[0]
            raise DataFormatError(f"{self.source}: {len(self.subckts)} subcircuits "
                                  f"({', '.join(s.name for s in self.subckts) or 'none'}); "
                                  "choose one with --subckt")
        found = self.find(name)
        if found is not None:
            return found
        crypt = (f"; its encrypted part ({self.encrypted[0].where}) cannot be read"
                 if self.encrypted else "")
        names = ", ".join(s.name for s in self.subckts[:20]) or "none"
        more = f" and {len(self.subckts) - 20} more" if len(self.subckts) > 20 else ""
        raise DataFormatError(f"{self.source}: no subcircuit {name!r} (there are: {names}{more})"
                              f"{crypt}")


def decode(raw: bytes, label: str) -> str:
    """The text of a library file: refuses binary and empty files in one line.

    >>> decode(b"R1 a b 1\\n", "x.lib")
    'R1 a b 1\\n'
    """
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        try:
            raw = raw.decode("utf-16").encode("utf-8")
        except UnicodeDecodeError:
            raise DataFormatError(f"{label}: not a SPICE library (bad UTF-16 text)") from None
    if raw.lstrip().startswith(b"<Binary File>"):
        raise DataFormatError(f"{label}: an LTspice binary (encrypted) library; an encrypted "
                              "model cannot be read")
    if b"\0" in raw:
        raise DataFormatError(f"{label}: a binary file (it holds NUL bytes), not a SPICE library")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")
    if not text.strip():
        raise DataFormatError(f"{label}: empty file, no subcircuit to read")
    return text


def _strip_comment(raw: str) -> str:
    """A physical line without its comment (``;``, ``//``, `` $ ``), stripped."""
    line = raw.split(";", 1)[0]
    cut = line.find("//")
    if cut >= 0 and (cut == 0 or line[cut - 1].isspace()):
        line = line[:cut]
    m = _DOLLAR.search(line)
    if m:
        line = line[:m.start()]
    return line.strip()


def logical_lines(text: str, file: str = "<text>") -> list[Line]:
    """Lines with ``+`` continuations joined and comments removed; ngspice ``.control`` blocks
    and everything after ``.end`` are dropped.

    >>> [l.text for l in logical_lines("* c\\nR1 a b 1k ; r\\n  + TC=0\\nC1 a 0 1u $ c\\n")]
    ['R1 a b 1k TC=0', 'C1 a 0 1u']
    """
    out: list[Line] = []
    control = False
    for k, raw in enumerate(text.splitlines(), 1):
        if raw.lstrip().startswith("*"):
            continue
        line = _strip_comment(raw)
        if not line:
            continue
        word = line.split()[0].lower()
        if control or word == ".control":
            control = word != ".endc"
            continue
        if word == ".end":
            break
        if line.startswith("+"):
            if not out:
                raise DataFormatError(f"{file}, line {k}: a continuation line with nothing to "
                                      "continue")
            out[-1] = Line(file, out[-1].number, f"{out[-1].text} {line[1:].strip()}")
        else:
            out.append(Line(file, k, line))
    return out


def assignments(text: str) -> dict[str, str]:
    """``a=1 b = {a*2}`` -> {"a": "1", "b": "{a*2}"} (names lower-cased).

    >>> assignments("Rth1 = {0.5} cth=1m k='2*x'")
    {'rth1': '{0.5}', 'cth': '1m', 'k': "'2*x'"}
    """
    out = {}
    for m in re.finditer(r"([a-z_][a-z0-9_]*)\s*=\s*(\{[^}]*\}|'[^']*'|\S+)", text, re.I):
        out[m.group(1).lower()] = m.group(2)
    return out


class _Reader:
    """Reads a library and the files it includes into a :class:`Library`."""

    def __init__(self, path: Path) -> None:
        self.root = path.resolve().parent
        self.lib = Library(str(path), [], [])
        self.stack: list[Subckt] = []
        self.seen: set[str] = set()

    def read(self, path: Path, label: str, section: str | None = None, depth: int = 0) -> None:
        real = os.path.realpath(path)
        if real in self.seen and section is None:
            return
        self.seen.add(real)
        text = decode(open_bounded(path, label, root=self.root if depth else None), label)
        lines = text.splitlines()
        self._encrypted(lines, label)
        sections = {m.group(1).lower() for m in re.finditer(r"^\s*\.lib\s+(\S+)\s*$", text,
                                                             re.I | re.M)} if section else set()
        if section is not None and section.lower() not in sections:
            self.lib.notes.append(f"{label}: no section {section!r}")
            return
        inside = section is None
        for line in logical_lines(text, label):
            words = line.text.split()
            word = words[0].lower()
            if section is not None and word in (".lib", ".endl"):
                if word == ".lib" and len(words) == 2:
                    inside = words[1].lower() == section.lower()
                elif word == ".endl":
                    inside = False
                continue
            if inside:
                self.line(line, words, word, path, depth)

    def _encrypted(self, lines: list[str], label: str) -> None:
        hexes = 0
        for k, raw in enumerate(lines, 1):
            if any(p.search(raw) for p in _ENCRYPTED):
                self.lib.encrypted.append(Line(label, k, raw.strip()))
                return
            hexes = hexes + 1 if _HEX_LINE.match(raw) else 0
            if hexes == 8:
                self.lib.encrypted.append(Line(label, k - 7, "hexadecimal block"))
                return

    def line(self, line: Line, words: list[str], word: str, path: Path, depth: int) -> None:
        if word == ".subckt":
            self.subckt(line)
        elif word == ".ends":
            if self.stack:
                self.stack.pop()
            else:
                self.lib.notes.append(f"{line.where}: .ENDS without .SUBCKT: ignored")
        elif word in (".include", ".inc") or (word == ".lib" and len(words) >= 2):
            self.include(line, words, path, depth)
        elif word == ".endl":
            return
        elif self.stack:
            self.stack[-1].body.append(line)
        elif word in (".param", ".params"):
            self.lib.params.append(line)
        elif word == ".func":
            self.lib.funcs.append(line)

    def subckt(self, line: Line) -> None:
        m = re.search(r"\s+params?\s*:", line.text, re.I)
        head, defaults = (line.text[:m.start()], line.text[m.end():]) if m else (line.text, "")
        opt = re.search(r"\s+optional\s*:", head, re.I)
        optional = assignments(head[opt.end():]) if opt else {}
        names = tuple(re.findall(r"([a-z_][\w$]*)\s*=", head[opt.end():], re.I)) if opt else ()
        head = head[:opt.start()] if opt else head
        words = re.sub(r"\s*=\s*", "=", head).split()
        if len(words) < 2:
            raise DataFormatError(f"{line.where}: .SUBCKT without a name")
        pins = tuple(w for w in words[2:] if "=" not in w)
        extra = " ".join(w for w in words[2:] if "=" in w)
        sub = Subckt(words[1], pins + names, line, assignments(f"{extra} {defaults}"),
                     parent=self.stack[-1] if self.stack else None, optional=optional)
        self.stack.append(sub)
        self.lib.subckts.append(sub)

    def include(self, line: Line, words: list[str], path: Path, depth: int) -> None:
        name = words[1].strip("'\"")
        target = (path.parent / name) if not Path(name).is_absolute() else Path(name)
        section = words[2] if words[0].lower() == ".lib" and len(words) > 2 else None
        if words[0].lower() == ".lib" and len(words) == 2 and not target.is_file():
            return  # ".lib NAME" starts a section of this file: read it as part of the file
        if depth + 1 > MAX_INCLUDE_DEPTH:
            raise DataFormatError(f"{line.where}: includes nested more than "
                                  f"{MAX_INCLUDE_DEPTH} deep")
        if not target.is_file():
            self.lib.notes.append(f"{line.where}: {name} not found, not read")
            return
        self.read(target, f"{line.file} > {name}", section, depth + 1)


def read_library(path: str | os.PathLike) -> Library:
    """Read the subcircuits and global parameters of a SPICE library file (and the files it
    includes).

    Parameters
    ----------
    path : str or os.PathLike
        The SPICE library file (``.lib``, ``.txt``, ``.mod``, ``.sub``, ``.cir``...).

    Returns
    -------
    Library
        Its subcircuits (in file order), ``.param`` and ``.func`` lines, encrypted parts.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "v.lib"
    >>> _ = p.write_text(".SUBCKT D Tj Tc PARAMS: k=2\\nR1 Tj Tc {k}\\nC1 Tj 0 1m\\n.ENDS\\n")
    >>> lib = read_library(p)
    >>> [(s.name, s.pins, s.defaults) for s in lib.subckts]
    [('D', ('Tj', 'Tc'), {'k': '2'})]
    """
    path = Path(path)
    reader = _Reader(path)
    reader.read(path, str(path))
    for sub in reader.stack:  # as simulators do: the file's end closes it
        reader.lib.notes.append(f"{sub.line.where}: .SUBCKT {sub.name} has no .ENDS: it ends "
                                "with the file")
    return reader.lib
