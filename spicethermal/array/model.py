"""The N-port thermal model of an array: a physical R/C network and its file format.

:class:`ArrayModel` is a network of resistors and grounded heat capacities whose first ``N``
nodes are the ports (the heaters, whose temperatures are measured); some resistors end at the
reference (``REF``: the ambient, or the heat sink). A fitted model is Cauer-like: per cell a
chain of nodes from its junction down, coupling conductances between the cells and to a common
substrate node (:mod:`.ansatz`). Its step-response matrix Z(t) is symmetric, positive
semidefinite at every time and shares its time constants (:mod:`.modal`). The file format is
``spicethermal-array-model/1`` (``docs/array-model-format.md``).

>>> from spicethermal.core.ladder import Foster
>>> from spicethermal.model import ThermalModel
>>> one = ArrayModel.from_thermal_model(ThermalModel(Foster.from_tau([1.0, 2.0], [1e-3, 1.0])))
>>> one.n_ports, round(float(one.modes.dc()[0, 0]), 9)
(1, 3.0)
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from ..core.errors import DataFormatError
from ..core.ladder import Foster
from ..core.network import Network
from ..core.rc_network import nodal_foster
from ..io.coupling import Port
from ..io.files import read_json, write_json
from ..io.jsondoc import JsonDocument
from ..model import ThermalModel
from .modal import Modes

__all__ = ["ARRAY_FORMAT", "REF", "ArrayModel", "Port", "is_array_document"]

ARRAY_FORMAT = "spicethermal-array-model/1"
#: The name of the reference node in the document (ambient or heat sink).
REF = "REF"
_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.\-]{0,31}")


def _finite(value: object, what: str, *, positive: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise DataFormatError(f"{what}: {value!r} is not a finite number")
    if positive and value <= 0:
        raise DataFormatError(f"{what}: {value!r} must be positive")
    return float(value)


@dataclass(frozen=True, eq=False)
class ArrayModel(JsonDocument):
    """N-port thermal network (see the module docstring).

    Attributes
    ----------
    ports : tuple of Port
        The ports, in order; they are the first nodes of the network.
    nodes : tuple of str
        Every node's name, the ports first.
    resistors : tuple of (int, int, float)
        ``(a, b, R)``: R (K/W) between nodes ``a`` and ``b``; ``b = -1`` is the reference.
    capacitors : tuple of (int, float)
        ``(a, C)``: heat capacity C (J/K) of node ``a`` to the thermal ground; every node
        has one.
    reference : str
        ``ambient`` or ``case``: what the reference node is.
    provenance : Mapping
        Where the model came from (the fit's report).
    """

    ports: tuple[Port, ...]
    nodes: tuple[str, ...]
    resistors: tuple[tuple[int, int, float], ...]
    capacitors: tuple[tuple[int, float], ...]
    reference: str = "ambient"
    provenance: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        n, ports = len(self.nodes), len(self.ports)
        if ports < 1 or n < ports:
            raise DataFormatError("array model: needs at least one port, and the ports among "
                                  "its nodes")
        names = [p.name for p in self.ports]
        if tuple(names) != tuple(self.nodes[:ports]):
            raise DataFormatError("array model: the first nodes must be the ports, in order")
        for name in self.nodes:
            if not isinstance(name, str) or not _NAME.fullmatch(name) or name == REF:
                raise DataFormatError(f"array model: node name {name!r}: use a letter or digit "
                                      f"then up to 31 letters, digits, '_', '.', '-' (not {REF})")
        if len(set(self.nodes)) != n:
            raise DataFormatError("array model: node names must be unique")
        for a, b, r in self.resistors:
            if not (0 <= a < n and -1 <= b < n and a != b) or not (math.isfinite(r) and r > 0):
                raise DataFormatError(f"array model: resistor ({a}, {b}, {r}) is not a positive "
                                      f"resistance between two nodes")
        held = [a for a, _ in self.capacitors]
        if sorted(held) != list(range(n)) or any(
                not (math.isfinite(c) and c > 0) for _, c in self.capacitors):
            raise DataFormatError("array model: every node needs one positive heat capacity")
        if self.reference not in ("ambient", "case"):
            raise DataFormatError(f"array model: reference {self.reference!r} must be ambient "
                                  f"or case")
        _ = self.modes  # a network without a steady state is refused here

    # -- the network ---------------------------------------------------------------------
    @property
    def n_ports(self) -> int:
        """Number of ports N."""
        return len(self.ports)

    @property
    def network(self) -> Network:
        """The nodal network (:class:`~spicethermal.core.network.Network`; the reference is
        node ``n``, where the capacitors also end)."""
        n = len(self.nodes)
        return Network(n, tuple((a, n if b < 0 else b, r) for a, b, r in self.resistors),
                       tuple((a, n, c) for a, c in self.capacitors))

    @cached_property
    def modes(self) -> Modes:
        """The modal form (:class:`~spicethermal.array.modal.Modes`)."""
        net = self.network
        return Modes.of(net.conductance(), net.node_capacitance(), self.n_ports)

    def zth(self, t_s: Sequence[float] | np.ndarray) -> np.ndarray:
        """Step-response matrix Z(t) (K/W), ``(len(t_s), N, N)``.

        Parameters
        ----------
        t_s : array_like
            Times after the power step, s.

        Returns
        -------
        NDArray
        """
        return self.modes.step(t_s)

    def self_model(self, port: int) -> ThermalModel:
        """The single-port model seen from ``port`` with the other heaters off: its exact
        Foster form (what a bench measuring that heater alone would fit).

        Parameters
        ----------
        port : int
            Port index.

        Returns
        -------
        ThermalModel
        """
        net = self.network
        r0, r, tau = nodal_foster(net.conductance(), net.capacitance(), port)
        if r0 > 0:  # cannot happen with a capacity at every node; kept for safety
            raise DataFormatError("array model: a port without heat capacity")
        return ThermalModel(Foster.from_tau(r, tau), reference=self.reference,
                            provenance={"array_port": self.ports[port].name})

    @classmethod
    def from_thermal_model(cls, model: ThermalModel, name: str = "TJ") -> ArrayModel:
        """The array of one port that is ``model`` (a linear ladder), as its Cauer network.

        Parameters
        ----------
        model : ThermalModel
            A linear model.
        name : str
            The port's name.

        Returns
        -------
        ArrayModel
        """
        if not model.is_linear:
            raise DataFormatError("an array model is linear: the model has device effects")
        cauer = model.with_topology("cauer").ladder.with_capacitances()
        n = cauer.order
        nodes = (name, *[f"{name}.{k}" for k in range(1, n)])
        res = tuple((k, k + 1 if k + 1 < n else -1, float(r)) for k, r in enumerate(cauer.r))
        caps = tuple((k, float(c)) for k, c in enumerate(cauer.c))
        return cls((Port(name),), nodes, res, caps, model.reference,
                   dict(model.provenance))

    # -- files ---------------------------------------------------------------------------
    def to_dict(self) -> dict:
        """The ``spicethermal-array-model/1`` document (``docs/array-model-format.md``).

        Returns
        -------
        dict
        """
        name = [*self.nodes]

        def node(i: int) -> str:
            return REF if i < 0 else name[i]

        return {
            "format": ARRAY_FORMAT,
            "reference": self.reference,
            "ports": [p.to_dict() for p in self.ports],
            "nodes": [{"name": nm, "c_j_per_k": c}
                      for nm, c in zip(self.nodes, self.capacities, strict=True)],
            "resistors": [{"a": node(a), "b": node(b), "r_k_per_w": r}
                          for a, b, r in self.resistors],
            "provenance": dict(self.provenance),
        }

    @property
    def capacities(self) -> np.ndarray:
        """Heat capacity of every node (J/K), in node order."""
        out = np.zeros(len(self.nodes))
        for a, c in self.capacitors:
            out[a] = c
        return out

    @classmethod
    def from_dict(cls, data: Mapping, source: str = "array model") -> ArrayModel:
        """Read a ``spicethermal-array-model/1`` document; errors name ``source`` and the key.

        Parameters
        ----------
        data : Mapping
            The parsed JSON.
        source : str
            Named in error messages.

        Returns
        -------
        ArrayModel
        """
        if not isinstance(data, Mapping) or data.get("format") != ARRAY_FORMAT:
            got = data.get("format") if isinstance(data, Mapping) else None
            raise DataFormatError(f"{source}: format {got!r} is not {ARRAY_FORMAT}")
        try:
            ports = tuple(Port.from_dict(p, f"{source}, ports[{i}]")
                          for i, p in enumerate(_list(data, "ports", source)))
            entries = _list(data, "nodes", source)
            nodes = tuple(_text(e, "name", f"{source}, nodes[{i}]") for i, e in enumerate(entries))
            index = {nm: i for i, nm in enumerate(nodes)} | {REF: -1}
            caps = tuple((i, _finite(_field(e, "c_j_per_k", f"{source}, nodes[{i}]"),
                                     f"{source}, nodes[{i}].c_j_per_k", positive=True))
                         for i, e in enumerate(entries))
            res = []
            for i, e in enumerate(_list(data, "resistors", source)):
                at = f"{source}, resistors[{i}]"
                a, b = (_text(e, k, at) for k in ("a", "b"))
                for k, nm in (("a", a), ("b", b)):
                    if nm not in index:
                        raise DataFormatError(f"{at}.{k}: {nm!r} is no node of the model")
                ia, ib = (index[a], index[b]) if index[a] >= 0 else (index[b], index[a])
                res.append((ia, ib, _finite(_field(e, "r_k_per_w", at), f"{at}.r_k_per_w",
                                            positive=True)))
            provenance = data.get("provenance", {}) or {}
            if not isinstance(provenance, Mapping):
                raise DataFormatError(f"{source}, provenance: must be an object")
            return cls(ports, nodes, tuple(res), caps, data.get("reference", "ambient"),
                       dict(provenance))
        except DataFormatError as exc:
            text = str(exc)
            raise DataFormatError(text if text.startswith(source) else f"{source}: {text}"
                                  ) from None

    def save(self, path: str | Path) -> Path:
        """Write the model file atomically.

        Parameters
        ----------
        path : str or Path
            The ``.json`` file.

        Returns
        -------
        Path
        """
        return write_json(path, self.to_dict())

    @classmethod
    def load(cls, path: str | Path) -> ArrayModel:
        """Read an array model file.

        Parameters
        ----------
        path : str or Path
            The ``.json`` file.

        Returns
        -------
        ArrayModel
        """
        return cls.from_dict(read_json(path), str(path))


def is_array_document(path: str | Path) -> bool:
    """Whether the JSON file ``path`` is an array model (by its ``format``).

    Parameters
    ----------
    path : str or Path
        A model file.

    Returns
    -------
    bool
    """
    doc = read_json(path)
    return isinstance(doc, Mapping) and doc.get("format") == ARRAY_FORMAT


def _list(data: Mapping, key: str, source: str) -> list:
    value = data.get(key)
    if not isinstance(value, list) or not value:
        raise DataFormatError(f"{source}, {key}: must be a non-empty list")
    return value


def _field(entry: object, key: str, at: str) -> object:
    if not isinstance(entry, Mapping) or key not in entry:
        raise DataFormatError(f"{at}: needs the key {key}")
    return entry[key]


def _text(entry: object, key: str, at: str) -> str:
    value = _field(entry, key, at)
    if not isinstance(value, str):
        raise DataFormatError(f"{at}.{key}: {value!r} is not a name")
    return value
