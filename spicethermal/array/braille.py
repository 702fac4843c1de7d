"""Braille cells and lines: dot positions, and text as dot patterns.

A Braille cell is two columns of three (six-dot) or four (eight-dot) dots, numbered down the
left column (1, 2, 3, then 7), then down the right one (4, 5, 6, then 8); dots are 2.5 mm
apart. :func:`cell_ports` gives the ports of an actuator array in that order (named ``D1`` ...
``D8``), or row by row for other grids; :func:`text_patterns` turns text into the set of raised
dots of every cell (six-dot literary Braille, letters, digits with their number sign omitted,
common punctuation; dots 7 and 8 stay down).

>>> [p.name for p in cell_ports(4, 2)][:4], cell_ports(4, 2)[6].y_mm
(['D1', 'D2', 'D3', 'D4'], 7.5)
>>> text_patterns("ab")
[(1,), (1, 2)]
"""

from __future__ import annotations

from ..core.errors import DataFormatError
from .model import Port

__all__ = ["BRAILLE", "DOT_PITCH_MM", "cell_ports", "text_patterns"]

#: Distance between neighbouring dots of a cell, mm (the usual Braille dot pitch).
DOT_PITCH_MM = 2.5

#: Six-dot Braille: the raised dots of each character (letters a–j repeat as digits 1–0).
BRAILLE: dict[str, tuple[int, ...]] = {
    " ": (), "a": (1,), "b": (1, 2), "c": (1, 4), "d": (1, 4, 5), "e": (1, 5),
    "f": (1, 2, 4), "g": (1, 2, 4, 5), "h": (1, 2, 5), "i": (2, 4), "j": (2, 4, 5),
    "k": (1, 3), "l": (1, 2, 3), "m": (1, 3, 4), "n": (1, 3, 4, 5), "o": (1, 3, 5),
    "p": (1, 2, 3, 4), "q": (1, 2, 3, 4, 5), "r": (1, 2, 3, 5), "s": (2, 3, 4),
    "t": (2, 3, 4, 5), "u": (1, 3, 6), "v": (1, 2, 3, 6), "w": (2, 4, 5, 6),
    "x": (1, 3, 4, 6), "y": (1, 3, 4, 5, 6), "z": (1, 3, 5, 6),
    ",": (2,), ";": (2, 3), ":": (2, 5), ".": (2, 5, 6), "!": (2, 3, 5), "?": (2, 3, 6),
    "'": (3,), "-": (3, 6), "(": (2, 3, 5, 6), ")": (2, 3, 5, 6), "#": (3, 4, 5, 6),
}
for _digit, _letter in zip("1234567890", "abcdefghij", strict=True):
    BRAILLE[_digit] = BRAILLE[_letter]

#: Column and row of each dot number in a cell.
_DOT_PLACE = {1: (0, 0), 2: (0, 1), 3: (0, 2), 4: (1, 0), 5: (1, 1), 6: (1, 2), 7: (0, 3),
              8: (1, 3)}


def cell_ports(rows: int, cols: int, pitch_mm: float = DOT_PITCH_MM) -> list[Port]:
    """The ports of a ``rows × cols`` actuator grid at ``pitch_mm``.

    Parameters
    ----------
    rows, cols : int
        Grid size; 3 × 2 and 4 × 2 are Braille cells (ports ``D1`` ... in dot order).
    pitch_mm : float
        Distance between neighbouring actuators, mm.

    Returns
    -------
    list of Port
        Braille dot order for a Braille cell, else row by row (``R1C1``, ``R1C2``, ...).
    """
    if rows < 1 or cols < 1 or not pitch_mm > 0:
        raise DataFormatError(f"array grid {rows} x {cols} at {pitch_mm} mm: rows, columns and "
                              f"pitch must be positive")
    if cols == 2 and rows in (3, 4):
        dots = range(1, 2 * rows + 1)
        return [Port(f"D{d}", _DOT_PLACE[d][0] * pitch_mm, _DOT_PLACE[d][1] * pitch_mm)
                for d in dots]
    return [Port(f"R{r + 1}C{c + 1}", c * pitch_mm, r * pitch_mm)
            for r in range(rows) for c in range(cols)]


def text_patterns(text: str) -> list[tuple[int, ...]]:
    """The raised dots of every character of ``text`` (six-dot Braille, lower-cased).

    Parameters
    ----------
    text : str
        Letters, digits, space and ``, ; : . ! ? ' - ( ) #``.

    Returns
    -------
    list of tuple of int
        One tuple of dot numbers per character.
    """
    out = []
    for k, ch in enumerate(text.lower()):
        if ch not in BRAILLE:
            raise DataFormatError(f"text: character {ch!r} at position {k + 1} has no Braille "
                                  f"pattern here (letters, digits, space, "
                                  f"{' '.join(sorted(c for c in BRAILLE if not c.isalnum()))})")
        out.append(BRAILLE[ch])
    return out
