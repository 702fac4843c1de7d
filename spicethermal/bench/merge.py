"""Adding a run's data sets to a bundle, losing nothing (docs/reliability.md).

A rerun gets a new file name (``cooling_3.csv``, ``calibration_2.csv``); a single section's
previous entry (calibration, forward, pwm, the Rth summary) moves to the manifest's ``superseded``
list and its file stays; only ``replace_names`` puts new data in the place of a listed file.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # pragma: no cover
    from ..io.bundle import Bundle

#: Data-set sections a procedure adds to, and the stem of their file names.
SECTIONS = {"calibrate": "calibration", "cooling": "cooling", "pwm": "pwm"}


def fresh_name(stem: str, taken: set[str]) -> str:
    """The first free file name for a data set: ``calibration.csv``, ``calibration_2.csv``,
    ...; cooling curves are numbered from 1 (``cooling_1.csv``). The name is added to
    ``taken``.

    >>> taken = {"cooling_1.csv", "pwm.csv"}
    >>> fresh_name("cooling", taken), fresh_name("pwm", taken), fresh_name("pwm", taken)
    ('cooling_2.csv', 'pwm_2.csv', 'pwm_3.csv')
    """
    k = 1
    while True:
        name = f"{stem}_{k}.csv" if k > 1 or stem in ("cooling", "coupling") else f"{stem}.csv"
        if name not in taken:
            taken.add(name)
            return name
        k += 1


def add_datasets(bundle: Bundle, new: dict, taken: set[str],
                 replace_names: Sequence[str] = ()) -> Bundle:
    """``bundle`` with the data sets of ``new`` added, none of its own dropped.

    Parameters
    ----------
    bundle : the bundle as it is on disk.
    new : section -> new data: ``calibration``, ``forward`` and ``pwm`` a table, ``cooling`` a
        list of tables, ``coupling`` a section, ``rth`` a summary dict (any may be missing).
    taken : every name in the bundle's directory (new names avoid them; updated).
    replace_names : listed files whose data sets the new ones of the same section replace
        (same name, same place); without them a new data set gets a new name and a single
        section's old entry moves to ``superseded`` (its file stays in the directory).

    Returns
    -------
    Bundle
        The merged bundle (not yet written).
    """
    superseded = list(bundle.extra.get("superseded", []))
    replace_left = list(replace_names)
    doc = bundle.manifest()

    def take(stem: str, old_name: str | None) -> str:
        if old_name is not None and old_name in replace_left:
            replace_left.remove(old_name)
            return old_name
        return fresh_name(stem, taken)

    changes: dict = {}
    for section in ("calibration", "pwm", "forward"):
        table = new.get(section)
        if table is None:
            continue
        old = getattr(bundle, section)
        name = take(section, old.file if old is not None else None)
        if old is not None and name != old.file:
            superseded.append({"section": section, **doc[section]})
        changes[section] = replace(table, file=name)
    if new.get("cooling"):
        cooling = list(bundle.cooling)
        for table in new["cooling"]:
            slot = next((i for i, c in enumerate(cooling) if c.file in replace_left), None)
            if slot is None:
                cooling.append(replace(table, file=fresh_name("cooling", taken)))
            else:
                replace_left.remove(cooling[slot].file)
                cooling[slot] = replace(table, file=bundle.cooling[slot].file)
        changes["cooling"] = tuple(cooling)
    if new.get("coupling") is not None:  # a new array measurement: the old one is superseded
        if bundle.coupling is not None:
            superseded.append({"section": "coupling", **doc["coupling"]})
        sec = new["coupling"]
        changes["coupling"] = replace(sec, curves=tuple(
            replace(c, file=fresh_name("coupling", taken)) for c in sec.curves))
    extra = dict(bundle.extra)
    if new.get("rth") is not None:
        if "rth" in extra:
            superseded.append({"section": "rth", **extra["rth"]})
        extra["rth"] = new["rth"]
    if superseded:
        extra["superseded"] = superseded
    return bundle.with_(extra=extra, **changes)
