"""Real thermal transients recorded by other tools, as bundles: PyRth's text files
(:func:`read_pyrth`) and T3Ster's exports (:func:`read_t3ster`), read by
:mod:`spicethermal.io.importers` and interpreted here.

The reference temperature is taken as the junction temperature at the end of the record
(``tref_steady_c``, the mean of the last 5 samples): the device is assumed back at its
reference by then, so Rth is the rise recorded over the whole transient.

The calibration may be a table or polynomial (converted as it stands) or a K-factor
(:class:`~spicethermal.io.datasets.KFactorLaw`). Given ``tref_c``, the temperature of the
device at the end of the record, any of them is re-anchored there (its slope kept, its level
moved: :func:`~spicethermal.identify.calibration.anchored`): the sensor voltage of a transient
often sits tens of mV away from the oven calibration's (another sense current, an amplifier
offset), so that the table alone puts a device at room temperature near 2 degC (the PyRth
MOSFET files: 0.608 V at the end of the record, where the table reads 0.558 V at 23.4 degC).
"""

from __future__ import annotations

import os
from dataclasses import replace

import numpy as np

from ..io.bundle import Bundle, CalibrationTable, CoolingTable, KFactorLaw
from ..io.importers import (
    END_SAMPLES,
    CalibrationLike,
    Record,
    calibration_table,
    pyrth_record,
    t3ster_record,
)
from .calibration import anchored
from .readings import converter


def _cooling_bundle(record: Record, calibration: CalibrationTable | KFactorLaw,
                    power_w: float, source: dict, tref_c: float | None) -> Bundle:
    cal = converter(calibration, "auto")
    v_end = float(np.mean(record.v_tsp_v[-END_SAMPLES:]))
    if tref_c is not None:
        calibration = cal = anchored(cal, v_end, tref_c)
        source = {**source, "anchored": f"{v_end:.6g} V (end of record) = {tref_c:g} degC"}
    tref = float(cal.temperature(v_end))
    cooling = CoolingTable(record.t_s, power_w, v_tsp_v=record.v_tsp_v, tref_steady_c=tref,
                           file=record.label, rows=record.rows,
                           extra={"tref_steady_from": f"mean of the last {END_SAMPLES} samples"})
    bundle = Bundle(device=record.device, reference="ambient", ambient_c=tref_c,
                    calibration=calibration, cooling=(cooling,), extra={"source": source})
    # checked above under the source's name; written as a plain file name
    return bundle.with_(cooling=(replace(cooling, file="cooling_1.csv"),), source=record.label)


def read_pyrth(path: str | os.PathLike, calibration: CalibrationLike | None = None,
               power_w: float = 1.0, device: str | None = None,
               tref_c: float | None = None) -> Bundle:
    """Read a PyRth transient text file (:func:`~spicethermal.io.importers.pyrth_record`) into
    a bundle.

    Parameters
    ----------
    path : the ``.txt`` file.
    calibration : (temp_c, v_tsp_v) pairs, a :class:`CalibrationTable` or a K-factor
        (:class:`~spicethermal.io.datasets.KFactorLaw`); required (the file has none).
    power_w : the heating power step, W (PyRth's files do not store it; 1 W nominal).
    device : a name for the bundle.
    tref_c : temperature of the device at the end of the record; re-anchors the calibration
        there (module docstring). Default: the calibration's own reading.

    Returns
    -------
    Bundle
        Calibration and one cooling curve with raw ``v_tsp_v``.

    Examples
    --------
    >>> from spicethermal.data import path
    >>> from spicethermal.io.importers import PYRTH_MOSFET_CALIBRATION
    >>> b = read_pyrth(path("pyrth_mosfet/MOSFET_dry.txt"), PYRTH_MOSFET_CALIBRATION,
    ...                tref_c=25.0)
    >>> print(b.calibration)
    K-factor calibration: K = -2.324 mV/K, 0.607995 V at 25 degC
    """
    record = pyrth_record(path, device)
    table = calibration_table(calibration, record.label)
    return _cooling_bundle(record, table, power_w,
                           {**record.source, "power_w_nominal": power_w}, tref_c)


def read_t3ster(raw: str | os.PathLike, pwr: str | os.PathLike | None = None,
                tco: str | os.PathLike | None = None, device: str | None = None,
                tref_c: float | None = None) -> Bundle:
    """Read a T3Ster measurement (``.raw`` + ``.pwr`` + ``.tco``,
    :func:`~spicethermal.io.importers.t3ster_record`) into a bundle.

    Parameters
    ----------
    raw : the ``.raw`` time response record.
    pwr : the power file; default the ``.pwr`` beside ``raw`` with the same stem.
    tco : the calibration; default the only ``.tco`` file in that directory.
    device : a name for the bundle.
    tref_c : temperature of the device at the end of the record (re-anchors the calibration).

    Returns
    -------
    Bundle
        The ``.tco`` calibration (kind ``polynomial`` when its header holds the line) and one
        cooling curve with raw ``v_tsp_v`` at the ``.pwr`` power.

    Examples
    --------
    >>> from spicethermal.data import path
    >>> b = read_t3ster(path("pyrth_mosfet/t3ster/T25_I-m5m-I-h600m_100s.raw"))
    >>> b.calibration.kind, round(b.cooling[0].power_w, 4)
    ('polynomial', 1.7541)
    """
    record = t3ster_record(raw, pwr, tco, device)
    return _cooling_bundle(record, record.calibration, record.power_w, record.source, tref_c)
