"""The release: how long the node takes to fall from the steady hold below a temperature.

After the hold the heater goes off (or down to a keep-warm duty) and the node cools; the
release time is when it first falls below ``release_c``, bisected on the exact response of a
linear model and interpolated on the averaged simulation otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..core.errors import DataFormatError, SimulationError
from ..io.jsondoc import JsonDocument
from ..model import Schedule
from .trajectory import bisect, time_grid

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from .dynamics import Dynamics


@dataclass(frozen=True)
class Release(JsonDocument):
    """Time for the node to fall from the steady hold to ``release_c`` at ``keep_warm_duty``.

    Attributes
    ----------
    release_c : float
        The temperature the node must fall below, °C.
    keep_warm_duty : float
        Duty kept during the release (0: power off).
    time_s : float
        Seconds from the end of the steady hold.

    Examples
    --------
    >>> r = Release(40.0, 0.0, 1.25)
    >>> Release.from_dict(r.to_dict()) == r
    True
    >>> print(r)
    release below 40 °C at duty 0: 1.25 s from the steady hold
    """

    release_c: float
    keep_warm_duty: float
    time_s: float

    def to_dict(self) -> dict[str, float]:
        """The ``"release"`` object of the ``spicethermal drive --json`` document.

        Returns
        -------
        dict
            ``release_c``, ``keep_warm_duty``, ``time_s``.
        """
        return {"release_c": self.release_c, "keep_warm_duty": self.keep_warm_duty,
                "time_s": self.time_s}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Release:
        """Rebuild the release from its :meth:`to_dict` document.

        Parameters
        ----------
        data : dict
            ``release_c``, ``keep_warm_duty`` and ``time_s``.

        Returns
        -------
        Release
            Equal to the one that wrote ``data``.
        """
        return cls(float(data["release_c"]), float(data["keep_warm_duty"]),
                   float(data["time_s"]))

    #: Deprecated spelling of :meth:`to_dict` (kept for existing callers).
    as_json = to_dict

    def __str__(self) -> str:
        return (f"release below {self.release_c:g} °C at duty {self.keep_warm_duty:g}: "
                f"{self.time_s:.4g} s from the steady hold")


def find_release(dyn: Dynamics, node: int, x_hold: NDArray, release_c: float,
                 keep_warm_duty: float, horizon: float) -> Release:
    """The release from the steady hold ``x_hold`` below ``release_c`` at ``keep_warm_duty``.

    Parameters
    ----------
    dyn : Dynamics
        Simulates the cool-down (its ``tref`` is the ambient).
    node : int
        The node that must fall below ``release_c``.
    x_hold : NDArray
        Node rises of the steady hold, K.
    release_c : float
        The temperature to fall below, °C (checked against the target by the caller).
    keep_warm_duty : float
        Duty kept during the release.
    horizon : float
        Longest time considered, s.

    Returns
    -------
    Release
    """
    ambient_c = dyn.tref
    rel_k = release_c - ambient_c
    floor = dyn.steady(dyn.p * keep_warm_duty)[node]
    if floor >= rel_k:
        raise DataFormatError(
            f"release below {release_c:g} °C is not reachable at keep-warm duty "
            f"{keep_warm_duty:g}: the node settles at {ambient_c + floor:.2f} °C")
    sched = Schedule((0.0,), (dyn.p * keep_warm_duty,))
    t = time_grid(dyn.period, horizon, (), 1500)
    y = dyn.model.simulate(t, sched, ambient_c, x_hold).theta_k[:, node]
    below = np.nonzero(y <= rel_k)[0]
    if below.size == 0:  # pragma: no cover - the floor check makes this unreachable
        raise SimulationError("release: the node did not fall below the release temperature")
    i = int(below[0])
    if i == 0:
        return Release(release_c, float(keep_warm_duty), 0.0)
    if dyn.linear:
        def f(tt: float) -> float:
            return dyn.model.simulate([tt], sched, ambient_c, x_hold).theta_k[0, node] - rel_k

        ts = bisect(f, float(t[i - 1]), float(t[i]))
    else:
        w = (y[i - 1] - rel_k) / (y[i - 1] - y[i])
        ts = float(t[i - 1] + w * (t[i] - t[i - 1]))
    return Release(release_c, float(keep_warm_duty), ts)
