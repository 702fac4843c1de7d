"""The simulated plant of an actuator array: one heater on at a time, one diode read at a time.

:class:`ArrayPlant` is a :class:`~spicethermal.bench.plant.Plant` whose network is the array's
(:class:`~spicethermal.bench.array_devices.ArrayGeometry`): the same exact modal stepping, for
constant power and for blocks of whole PWM periods, with the heat going into the heater the
board's multiplexer selects (``heater``), and the TSP reading the diode its other multiplexer
selects (``tsp_port``). The array is linear (no device effects).

>>> from spicethermal.bench.devices import preset
>>> from spicethermal.bench.array_devices import ArrayGeometry
>>> p = ArrayPlant(preset("array"), ArrayGeometry(rows=1, cols=2))
>>> p.heater = 1
>>> p.step(1e4, 0.1)        # heater 2 on for a long time
>>> p.tsp_port = 0
>>> round(p.sensed_c - p.ambient_c(), 3) < round(p.tj_c - p.ambient_c(), 3)
True
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .array_devices import ArrayGeometry
from .plant import Plant

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from .devices import Preset

__all__ = ["ArrayPlant"]


class ArrayPlant(Plant):
    """Thermal state of a simulated actuator array (see the module docstring).

    Parameters
    ----------
    preset : Preset
        The device preset (ambient, reference, diode and board).
    geometry : ArrayGeometry
        The array.

    Attributes
    ----------
    model : ArrayModel
        The array's true network.
    heater : int
        The port the heating power goes into.
    tsp_port : int
        The port whose diode the TSP channel reads.
    """

    def __init__(self, preset: Preset, geometry: ArrayGeometry) -> None:
        self.preset = preset
        self.model = geometry.model()
        net = self.model.network
        self.c0, self.g0 = net.node_capacitance(), net.conductance()
        self.n = len(self.model.nodes)
        self.device_effects = ()
        self.heater = 0
        self.tsp_port = 0
        self._inputs: dict[int, NDArray] = {}
        self._reset()

    @property
    def n_ports(self) -> int:
        """Number of heaters."""
        return self.model.n_ports

    @property
    def tj_c(self) -> float:
        """The heated diode's junction (its forward voltage sets the heating power)."""
        return self.base_c + float(self.theta[self.heater])

    @property
    def sensed_c(self) -> float:
        """The junction of the diode the TSP multiplexer selects."""
        return self.base_c + float(self.theta[self.tsp_port])

    def _modal(self) -> tuple[NDArray, NDArray, NDArray, NDArray]:
        if self._modal_cache is None:
            self._modal_cache = self._decompose(self.c0, self.g0)
        lam, w, w_inv, _ = self._modal_cache
        q = self._inputs.get(self.heater)
        if q is None:
            e = np.zeros(self.n)
            e[self.heater] = 1.0
            q = self._inputs[self.heater] = w_inv @ (e / self.c0)
        return lam, w, w_inv, q
