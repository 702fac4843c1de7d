"""A simulated production population: many samples of one part, with manufacturing spread and
a few planted defects, written as real measurement bundles.

Every device is a Cauer ladder of the layers of :data:`LAYERS` (junction outwards: die, die
attach, base, interface), each layer's R and C drawn log-normally around the nominal value
with a relative spread ``spread`` (the manufacturing tolerance of thickness, area,
conductivity). A *voided die attach* — the classic assembly defect — removes part of the
solder's cross-section: its resistance rises ``void_factor`` times (drawn in
:data:`VOID_FACTOR`) and its capacitance falls by the voided fraction. It shows as extra
resistance beyond the die in the structure function, i.e. a larger outer resistance seen from
the junction, which is what :mod:`spicethermal.batch.spread` must find.

Each bundle holds one cooling curve after ``power_w`` is cut from the steady state, sampled
10 points per decade from 3 µs to 100 s with white noise ``noise_k``
(:func:`spicethermal.core.synthetic.synthetic_cooling`), the steady state just before the cut
read with the same noise. The truth (layers and defects) goes into ``population.json`` beside
the bundles, never into them.

>>> pop = simulate_population(20, seed=3, defects=2)
>>> len(pop), sum(d.defect is not None for d in pop)
(20, 2)
>>> round(pop[0].cauer.rth / nominal_cauer().rth, 2)
0.99
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import DataFormatError
from ..core.ladder import Cauer
from ..core.synthetic import synthetic_cooling
from ..io.bundle import Bundle, CoolingTable
from ..io.files import atomic_write_text, dumps_json

if TYPE_CHECKING:  # pragma: no cover
    import os

__all__ = ["DEFECT", "LAYERS", "SimulatedDevice", "nominal_cauer", "simulate_population",
           "write_population"]

#: Layers of the simulated part, junction outwards: (name, R in K/W, C in J/K). Rth 1.5 K/W,
#: time constants about 10 µs, 1 ms, 0.1 s and 6 s, a decade or more apart.
LAYERS = (("die", 0.05, 2e-4), ("die attach", 0.20, 5e-3), ("base", 0.35, 0.3),
          ("interface", 0.90, 6.0))
#: The planted defect and the layer it affects.
DEFECT = "voided die attach"
DEFECT_LAYER = 1
#: Range of the voided die attach's resistance factor (uniform).
VOID_FACTOR = (2.0, 4.0)
#: Cooling record: 10 points per decade from 3 µs to 100 s.
T_COOL_S = 10.0 ** (np.arange(-55, 21) / 10)
AMBIENT_C = 25.0


def nominal_cauer() -> Cauer:
    """The nominal part: the Cauer ladder of :data:`LAYERS`."""
    return Cauer([r for _, r, _ in LAYERS], [c for _, _, c in LAYERS])


@dataclass(frozen=True)
class SimulatedDevice:
    """One sample: its name, true Cauer ladder and planted defect (None for a good part)."""

    name: str
    cauer: Cauer
    defect: str | None = None
    void_factor: float = 1.0

    def to_dict(self) -> dict:
        """JSON-ready truth of the sample."""
        return {"name": self.name, "defect": self.defect, "void_factor": self.void_factor,
                "layers": [{"layer": name, "r_k_per_w": r, "c_j_per_k": c}
                           for (name, _, _), r, c in zip(LAYERS, self.cauer.r, self.cauer.c,
                                                         strict=True)]}


def simulate_population(n: int, seed: int = 0, *, defects: int | None = None,
                        spread: float = 0.05) -> list[SimulatedDevice]:
    """``n`` samples with log-normal spread ``spread`` (relative standard deviation of every
    layer's R and C) and ``defects`` voided die attaches (default 3 % of ``n``, at least 1),
    placed at seeded random positions.

    Parameters
    ----------
    n : number of devices (>= 1).
    seed : random seed; the same seed gives the same population.
    defects : number of planted defects (0 to ``n``).
    spread : relative manufacturing spread of each R and C (>= 0).

    Returns
    -------
    list of SimulatedDevice, named ``device_001`` ...

    Examples
    --------
    >>> [d.name for d in simulate_population(2, defects=0)]
    ['device_001', 'device_002']
    """
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise DataFormatError(f"n = {n!r}: the population needs at least one device")
    n_bad = max(1, round(0.03 * n)) if defects is None else int(defects)
    if not 0 <= n_bad <= n:
        raise DataFormatError(f"defects = {defects!r}: must be between 0 and {n}")
    if not (np.isfinite(spread) and spread >= 0):
        raise DataFormatError(f"spread = {spread!r}: must be >= 0")
    rng = np.random.default_rng(seed)
    nominal = nominal_cauer()
    bad = set(rng.choice(n, size=n_bad, replace=False).tolist())
    width = len(str(n)) if n >= 1000 else 3
    out = []
    for i in range(n):
        r = np.asarray(nominal.r) * np.exp(rng.normal(0.0, spread, nominal.order))
        c = np.asarray(nominal.c) * np.exp(rng.normal(0.0, spread, nominal.order))
        factor = float(rng.uniform(*VOID_FACTOR))
        defect = None
        if i in bad:
            defect = DEFECT
            r[DEFECT_LAYER] *= factor
            c[DEFECT_LAYER] /= factor  # the voided fraction of the solder holds no heat
        out.append(SimulatedDevice(f"device_{i + 1:0{width}d}", Cauer(r, c), defect,
                                   factor if defect else 1.0))
    return out


def device_bundle(device: SimulatedDevice, *, power_w: float = 20.0, noise_k: float = 0.02,
                  seed: int = 0) -> Bundle:
    """The bundle the bench would record from ``device`` (module docstring)."""
    t, tj = synthetic_cooling(device.cauer, power_w, T_COOL_S, noise_k, seed,
                              ambient_c=AMBIENT_C)
    top = AMBIENT_C + power_w * device.cauer.rth
    top += float(np.random.default_rng([seed, 1]).normal(0.0, noise_k)) if noise_k else 0.0
    cooling = CoolingTable(t, power_w, tj_c=np.round(tj, 5), tj_steady_c=round(top, 5),
                           tref_steady_c=AMBIENT_C, file="cooling_1.csv")
    return Bundle(device=f"simulated part, {device.name}", ambient_c=AMBIENT_C,
                  cooling=(cooling,))


def write_population(out_dir: str | os.PathLike, n: int, seed: int = 0, *,
                     defects: int | None = None, spread: float = 0.05, power_w: float = 20.0,
                     noise_k: float = 0.02) -> list[SimulatedDevice]:
    """Write ``n`` simulated bundles into ``out_dir`` (one directory per device) and the truth
    into ``out_dir/population.json``; return the devices.

    >>> import tempfile
    >>> out = Path(tempfile.mkdtemp())
    >>> devices = write_population(out, 3, defects=1)
    >>> sorted(p.name for p in out.iterdir())
    ['device_001', 'device_002', 'device_003', 'population.json']
    """
    out = Path(out_dir)
    devices = simulate_population(n, seed, defects=defects, spread=spread)
    for i, device in enumerate(devices):
        device_bundle(device, power_w=power_w, noise_k=noise_k, seed=seed * 100003 + i
                      ).write(out / device.name)
    truth = {"format": "spicethermal-population/1", "seed": seed, "spread": spread,
             "power_w": power_w, "noise_k": noise_k, "defect_layer": LAYERS[DEFECT_LAYER][0],
             "devices": [d.to_dict() for d in devices]}
    atomic_write_text(out / "population.json", dumps_json(truth, indent=1) + "\n")
    return devices
