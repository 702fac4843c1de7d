"""LSODA to a list of readings, in ODEPACK's own loop: the integrator behind the forward
model of a latent heat's cooling curves (:mod:`spicethermal.fit.pcforward`).

``scipy.integrate.solve_ivp`` drives LSODA one step at a time from Python, and its per-step
overhead (the step's bookkeeping, the events, the dense output) costs two to three times the
right-hand sides of these small networks. Here ODEPACK integrates from one reading to the next
by itself (``itask = 4``: never past the last reading, whose time is its critical time), so a
cooling curve costs its right-hand sides and little else.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import SimulationError

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

__all__ = ["lsoda_until"]

#: Steps allowed between two readings (a budget or a count of right-hand sides stops a
#: runaway integration first).
NSTEPS = 10**7


def lsoda_until(rhs: Callable[[float, NDArray], NDArray],
                jac: Callable[[float, NDArray], NDArray], theta0: NDArray,
                t_sorted: NDArray, first_step: float, rtol: float, atol: float,
                what: str, stop: Callable[[NDArray], bool] | None = None
                ) -> tuple[NDArray, NDArray]:
    """``θ[0]`` at the sorted times ``t_sorted`` (s, from 0) of ``dθ/dt = rhs(t, θ)`` from
    ``θ(0) = theta0``, with the Jacobian ``jac``, up to and including the first reading whose
    state satisfies ``stop``; returns those values and the state at the last reading.

    Raises
    ------
    SimulationError
        When LSODA fails (``what`` names the integration in the message); what ``rhs`` or
        ``jac`` raise (a time budget) goes through.

    >>> g = np.array([[2.0, -1.0], [-1.0, 1.0]])
    >>> rise, _ = lsoda_until(lambda _t, y: -g @ y, lambda _t, _y: -g, np.array([1.0, 1.0]),
    ...                       np.array([0.0, 0.5, 2.0]), 1e-4, 1e-9, 1e-12, "a test")
    >>> lam, v = np.linalg.eigh(g)
    >>> exact = [((v * np.exp(-lam * t)) @ (v.T @ [1.0, 1.0]))[0] for t in (0.0, 0.5, 2.0)]
    >>> bool(np.allclose(rise, exact, rtol=1e-7))
    True
    """
    from scipy.integrate import ode

    solver = ode(rhs, jac)
    solver.set_integrator("lsoda", rtol=rtol, atol=atol, first_step=first_step,
                          max_step=0.0, min_step=0.0, nsteps=NSTEPS)
    solver.set_initial_value(theta0, 0.0)
    task = solver._integrator  # noqa: SLF001 (ODEPACK's task and critical time)
    task.rwork[0] = float(t_sorted[-1])
    task.call_args[4] = task.rwork
    task.call_args[2] = 4
    out = np.empty(t_sorted.size)
    theta = np.asarray(theta0, dtype=float)
    with warnings.catch_warnings():  # a failed integration is reported by successful()
        warnings.simplefilter("ignore")
        for k, tk in enumerate(t_sorted):
            if tk > 0:
                theta = solver.integrate(float(tk))
                if not solver.successful():
                    raise SimulationError(f"{what} integration failed at {tk:.3g} s (LSODA "
                                          f"state {task.istate})")
            out[k] = theta[0]
            if stop is not None and stop(theta):
                return out[:k + 1], np.array(theta)
    return out, np.array(theta)
