"""Thermal networks in series: a device's junction-to-case, an interface, a heatsink or board
to ambient, as one Cauer ladder.

Each network's reference node is the next one's junction: the resistors follow one another,
the capacities stay at their nodes, and a network's **case capacity** (the heat capacity of
its reference node) joins the capacity of the next network's first node. A Cauer ladder is the
form in which networks couple (its capacities go to the thermal ground); a Foster network is
first converted to its exact Cauer equivalent (:meth:`~spicethermal.core.ladder.Foster.to_cauer`:
the same Zth with its reference held, its nodes those of the equivalent ladder).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from .errors import DataFormatError
from .ladder import Cauer, Foster


@dataclass(frozen=True)
class Chained:
    """The composed ladder, the capacity of its last reference node, the index of each part's
    first node, and whether each part was converted from Foster."""

    ladder: Cauer
    case_c: float
    starts: tuple[int, ...]
    converted: tuple[bool, ...]


def chain(parts: Sequence[tuple[Foster | Cauer, float]]) -> Chained:
    """Networks ``(ladder, case capacity)`` in series, junction first.

    Parameters
    ----------
    parts : sequence of (Foster or Cauer, float)
        Each network and the heat capacity (J/K) of its reference node.

    Returns
    -------
    Chained

    Examples
    --------
    >>> part = (Cauer([1.0, 2.0], [0.1, 0.2]), 0.5)
    >>> sink = (Cauer([3.0], [4.0]), 0.0)
    >>> out = chain([part, sink])
    >>> out.ladder.r, out.ladder.c, out.starts
    ((1.0, 2.0, 3.0), (0.1, 0.2, 4.5), (0, 2))
    """
    if len(parts) < 2:
        raise DataFormatError("compose: give at least two networks (a part and what it is "
                              "mounted on)")
    r: list[float] = []
    c: list[float] = []
    starts, converted = [], []
    carry = 0.0
    for ladder, case_c in parts:
        cauer = ladder.to_cauer() if isinstance(ladder, Foster) else ladder
        converted.append(isinstance(ladder, Foster))
        starts.append(len(r))
        r += list(cauer.r)
        c += [cauer.c[0] + carry, *cauer.c[1:]]
        carry = float(case_c)
    return Chained(Cauer(r, c), carry, tuple(starts), tuple(converted))
