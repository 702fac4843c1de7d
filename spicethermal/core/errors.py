"""The exception hierarchy. The command line turns any of these into one line and exit code 2."""

from __future__ import annotations


class SpiceThermalError(Exception):
    """Base class of every error spicethermal raises on purpose."""


class DataFormatError(SpiceThermalError, ValueError):
    """Bad input data: names the file, row, column or parameter."""


class FitError(SpiceThermalError):
    """A fit that cannot be done or did not converge."""


class InstrumentError(SpiceThermalError):
    """The bench (or its simulator) failed: port, timeout, protocol, firmware version."""


class SimulationError(SpiceThermalError):
    """A circuit simulator failed or produced something unusable."""


class BusyError(SpiceThermalError):
    """Another process holds the lock of the bundle this one wants to change."""


def where(file: object = None, row: int | None = None, column: str | None = None) -> str:
    """Format a location prefix such as ``cooling_1.csv, row 12, column tj_c: ``.

    >>> where("a.csv", 3, "t_s")
    'a.csv, row 3, column t_s: '
    """
    parts = []
    if file is not None:
        parts.append(str(file))
    if row is not None:
        parts.append(f"row {row}")
    if column is not None:
        parts.append(f"column {column}")
    return ", ".join(parts) + ": " if parts else ""
