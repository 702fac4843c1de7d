"""Data sets shipped with spicethermal; :func:`path` gives the location of one of them.

* ``mur880e_table1.csv`` — the paper's Table 1: MUR880E normalized junction-to-case thermal
  impedance r(t) at 10 us ... 1 s, datasheet and measured (Rthjc = 1.51 K/W). Loaded by
  :func:`spicethermal.datasheet.mur880e`.
* ``actuator_table2.csv`` — the paper's Table 2: measured vs PSPICE-simulated junction
  temperature of the thermopneumatic actuator under PWM (18 points).
* ``sample_bundle/`` — a measurement bundle of the simulated actuator (calibration, two
  cooling curves, the 18-point PWM grid), the README tutorial's sample data.
* ``pyrth_mosfet/`` — real cooling transients of a power MOSFET mounted dry and with a thermal
  interface material, and one T3Ster export, from the PyRth project (MIT licence, see
  ``pyrth_mosfet/README.md`` and ``pyrth_mosfet/LICENSE.txt``).
* ``vendor/`` — vendors' thermal networks (Infineon, LT SOAtherm for Infineon, Fairchild and
  IR parts, Fairchild): short excerpts of public SPICE libraries, sources and terms in
  ``vendor/README.md``; read by ``spicethermal import`` in the tests and the README.
* ``heatsink_zth.csv`` — an example heatsink Zth(t), base to ambient (a stand-in for a
  measurement, made from a three-layer model with 0.2 % noise: see its header); the README's
  ``compose`` example fits it.
* ``model.schema.json`` — the JSON Schema of the model file (``docs/model-format.md``).
* ``sim_bench.json`` — the simulated bench's data: each device preset's device effects (as a
  model file holds them) and the catalogued effect each artefact of its front end shows as
  (:mod:`spicethermal.bench.devices`).
"""

from __future__ import annotations

from pathlib import Path

_HERE = Path(__file__).resolve().parent


def path(name: str) -> Path:
    """Location of a shipped data file.

    Parameters
    ----------
    name : str
        Path relative to the data folder, e.g. ``"actuator_table2.csv"`` or
        ``"pyrth_mosfet/MOSFET_dry.txt"``.

    Returns
    -------
    Path
        The file's absolute path.

    Examples
    --------
    >>> path("actuator_table2.csv").name
    'actuator_table2.csv'
    """
    p = (_HERE / name).resolve()
    if _HERE not in p.parents or not p.is_file():
        raise FileNotFoundError(f"no shipped data file {name!r}")
    return p
