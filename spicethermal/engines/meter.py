"""The simulator's work, counted: network *solves* and the batched *steps* they are done in.

:class:`~spicethermal.engines.network.NetworkBatch` charges every frozen network it solves
(:func:`charge`); :func:`metered` counts what a block of code charged. Budgets of work (the
diagnosis's) are counted in this cost, never in time, so that the same input gives the same
result on every machine and under any load.

>>> import numpy as np
>>> from spicethermal.engines.network import NetworkBatch
>>> with metered() as meter:
...     _ = NetworkBatch(np.ones((3, 2)), np.ones((3, 2))).foster()
>>> meter.solves, meter.steps, meter.cost
(3, 1, 63)
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass

__all__ = ["SOLVE_NODES", "STEP_SOLVES", "Meter", "charge", "metered"]

#: What one batched step of the simulator costs beyond its members, in solves: a step's numpy
#: calls (a few dozen on small arrays) take about 200 µs whatever the batch, where each member
#: adds 3 to 4 µs (its modes, its effects' terms), fitted over the diagnoses of eight bundles
#: on the bench's 2-core machine. A batch of a few members costs its step, not its members.
STEP_SOLVES = 60
#: Nodes up to which a member's solve costs one: beyond, a member of ``n`` nodes counts
#: ``(n / SOLVE_NODES)²`` solves, as its eigendecomposition (and a steady state's Newton
#: solve) grows on these sizes: about 1, 3, 6 and 9.5 µs a member and step at 3, 6, 9 and 12
#: nodes on the bench's machine.
SOLVE_NODES = 7


@dataclass(eq=False)
class Meter:
    """The simulator's work counted by :func:`metered`: the network *solves* (one member's
    frozen network, in its modes), the batched *steps* they were done in (one frozen network
    per member each), and their ``cost``, ``solves + STEP_SOLVES × steps``, proportional to
    the CPU time they take."""

    solves: int = 0
    steps: int = 0

    @property
    def cost(self) -> int:
        return self.solves + STEP_SOLVES * self.steps


_METER: ContextVar[Meter | None] = ContextVar("spicethermal_network_meter", default=None)


@contextmanager
def metered() -> Iterator[Meter]:
    """Count the network solves done inside the ``with`` block (in this thread or task); an
    enclosing count gets them too."""
    meter, outer = Meter(), _METER.get()
    token = _METER.set(meter)
    try:
        yield meter
    finally:
        _METER.reset(token)
        if outer is not None:
            outer.solves += meter.solves
            outer.steps += meter.steps


def charge(solves: int, nodes: int = 0) -> None:
    """Charge one batched step of ``solves`` frozen networks of ``nodes`` nodes each to the
    running count, if any (:data:`SOLVE_NODES`)."""
    meter = _METER.get()
    if meter is not None:
        meter.solves += solves if nodes <= SOLVE_NODES else math.ceil(
            solves * (nodes / SOLVE_NODES) ** 2)
        meter.steps += 1
