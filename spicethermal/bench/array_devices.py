"""The simulated actuator array: cells of the paper's actuator on a common substrate.

Every cell is the ``actuator`` preset's ladder (:mod:`.devices`) as its Cauer network (die,
brass, cavity, body). Its last resistance, the body's path to the ambient, is split: a share
``base_share`` goes to a common substrate (a carrier plate of heat capacity
``substrate_c_j_per_k`` on a heat sink of ``substrate_r_k_per_w``), the rest through the air.
Neighbouring cells (the nearest and the diagonal ones, :func:`spicethermal.array.ansatz.neighbours`)
are joined through the substrate plate at their bases and through the air between the cavities
one level up, with conductances ``coupling × g_ref × (2.5 mm / d)²`` at distance ``d``. So an
array of one on an ideal heat sink is the single actuator, and with the defaults a 2 × 4 Braille
cell couples 6–19 % mutual/self at steady state.

>>> m = ArrayGeometry().model()
>>> m.n_ports, len(m.nodes)
(8, 33)
"""

from __future__ import annotations

from dataclasses import dataclass

from ..array.ansatz import Layout, neighbours
from ..array.braille import cell_ports
from ..array.model import ArrayModel
from ..core.errors import InstrumentError
from .devices import preset

__all__ = ["ARRAY_KEYS", "ArrayGeometry"]

#: Reference distance of the coupling conductances, mm.
D_REF_MM = 2.5
#: Coupling conductances at the reference distance, W/K: bases (through the substrate) and
#: cavities (through the air and the housing).
G_BASE_W_PER_K = 0.03
G_CAVITY_W_PER_K = 0.003
#: The options of a ``sim://array`` URL that shape the array.
ARRAY_KEYS = ("rows", "cols", "pitch", "coupling")


@dataclass(frozen=True)
class ArrayGeometry:
    """A simulated actuator array (see the module docstring).

    Attributes
    ----------
    rows, cols : int
        The grid (4 × 2: an eight-dot Braille cell).
    pitch_mm : float
        Distance between neighbouring actuators, mm.
    coupling : float
        Scale of every coupling conductance (0: independent cells).
    base_share : float
        Share of a cell's last conductance that goes to the substrate (the rest: the air).
    substrate_r_k_per_w, substrate_c_j_per_k : float
        The substrate's resistance to the ambient and its heat capacity.
    """

    rows: int = 4
    cols: int = 2
    pitch_mm: float = 2.5
    coupling: float = 1.0
    base_share: float = 0.5
    substrate_r_k_per_w: float = 8.0
    substrate_c_j_per_k: float = 1.0

    def __post_init__(self) -> None:
        if not (1 <= self.rows <= 8 and 1 <= self.cols <= 8):
            raise InstrumentError(f"sim://array: rows {self.rows}, cols {self.cols}: 1 to 8 each")
        if not (self.pitch_mm > 0 and self.coupling >= 0 and 0 < self.base_share <= 1
                and self.substrate_r_k_per_w > 0 and self.substrate_c_j_per_k > 0):
            raise InstrumentError("sim://array: pitch, substrate resistance and capacity must be "
                                  "positive, coupling >= 0, base share in (0, 1]")

    @classmethod
    def from_options(cls, opts: dict[str, str]) -> ArrayGeometry:
        """The geometry from a URL's options (``rows``, ``cols``, ``pitch`` mm, ``coupling``).

        Parameters
        ----------
        opts : dict of str to str
            The URL's query options.

        Returns
        -------
        ArrayGeometry
        """
        try:
            return cls(rows=int(opts.get("rows", 4)), cols=int(opts.get("cols", 2)),
                       pitch_mm=float(opts.get("pitch", 2.5)),
                       coupling=float(opts.get("coupling", 1.0)))
        except ValueError as exc:
            raise InstrumentError(f"sim://array: bad option value ({exc})") from None

    def model(self) -> ArrayModel:
        """The array's true network.

        Returns
        -------
        ArrayModel
        """
        cauer = preset("actuator").foster.to_cauer()
        ports = cell_ports(self.rows, self.cols, self.pitch_mm)
        n, levels = len(ports), cauer.order
        near = neighbours(ports) if n > 1 and self.coupling > 0 else []
        lateral = tuple((lv, i, j) for lv in (levels - 1, levels - 2) for i, j in near)
        layout = Layout(tuple(ports), levels, lateral, air=self.base_share < 1)
        g_last = 1.0 / cauer.r[-1]
        g = [1.0 / r for r in cauer.r[:-1]] + [g_last * self.base_share]
        g = g * n
        for lv, i, j in lateral:
            d = ((ports[i].x_mm - ports[j].x_mm) ** 2 + (ports[i].y_mm - ports[j].y_mm) ** 2
                 ) ** 0.5
            ref = G_BASE_W_PER_K if lv == levels - 1 else G_CAVITY_W_PER_K
            g.append(self.coupling * ref * (D_REF_MM / d) ** 2)
        if layout.air:
            g += [g_last * (1 - self.base_share)] * n
        g.append(1.0 / self.substrate_r_k_per_w)
        c = list(cauer.c) * n + [self.substrate_c_j_per_k]
        return layout.model(g, c, "ambient", {
            "device": f"simulated {self.rows} x {self.cols} actuator array, pitch "
                      f"{self.pitch_mm:g} mm"})
