"""``ThermalModel``: a ladder plus its effects, simulated under any power excitation.

A linear model (no device effects) is solved in closed form. Device effects make the model
nonlinear; it is then integrated as the nodal network the SPICE export describes,
``Cm(θ) dθ/dt = b·P(t) − G(θ)·θ`` with θ the node rises over the reference, by the network
simulator's exponential steps (:meth:`~spicethermal.engines.network.NetworkBatch.response`).
The PWM periodic steady state of a nonlinear model is found by shooting (a chord-Newton
iteration on the one-period map, its Jacobian from the network frozen at the current state),
which needs a handful of periods instead of the thousands a cold start needs.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING

import numpy as np

from .core.diode import DiodeLaw
from .core.errors import DataFormatError, SimulationError
from .core.ladder import Cauer, Foster
from .core.network import Network, Schedule, Trajectory, linear_response
from .effects import DEVICE, Effect
from .engines.cauer import as_cauer
from .engines.network import TOL_REL, NetworkBatch
from .engines.pwm import PwmState, check_drive, steady_state
from .io.files import atomic_write_text, dumps_json, read_json

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray

MODEL_FORMAT = "spicethermal-model/3"
#: The version that adds the ``electrical`` key (the heater's Vf(I, T)); a model without it is
#: written as /3, which older readers read.
MODEL_FORMAT_ELECTRICAL = "spicethermal-model/4"
#: Model-file formats :meth:`ThermalModel.from_dict` reads (see docs/model-format.md).
MODEL_FORMATS_READ = ("spicethermal-model/1", "spicethermal-model/2", MODEL_FORMAT,
                      MODEL_FORMAT_ELECTRICAL)
REFERENCES = ("ambient", "case")


@dataclass(frozen=True)
class ThermalModel:
    """A ladder and its effects: what ``spicethermal fit`` writes and ``export`` reads.

    >>> m = ThermalModel(Foster.from_tau([100.0], [1.0]))
    >>> round(m.pwm(0.1, 1e3, 0.5).mean_k, 9)
    5.0
    """

    ladder: Foster | Cauer
    effects: tuple[Effect, ...] = ()
    reference: str = "ambient"
    provenance: Mapping = field(default_factory=dict)
    #: Heat capacity (J/K) of the reference node itself (a vendor's case capacitance): inert
    #: with an ideal reference, exported to the thermal ground when coupled.
    case_c_j_per_k: float = 0.0
    #: The heater diode's forward voltage Vf(I, T) (``export --electrothermal``), or None.
    electrical: DiodeLaw | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.ladder, Foster | Cauer):
            raise DataFormatError("model: ladder must be a Foster or Cauer network")
        if not (math.isfinite(self.case_c_j_per_k) and self.case_c_j_per_k >= 0):
            raise DataFormatError(f"model: case_c_j_per_k = {self.case_c_j_per_k!r} must be "
                                  "finite and >= 0")
        if self.reference not in REFERENCES:
            raise DataFormatError(f"model: reference {self.reference!r} must be one of "
                                  f"{', '.join(REFERENCES)}")
        effects = tuple(e if isinstance(e, Effect) else Effect.from_dict(e) for e in self.effects)
        names = [e.name for e in effects]
        if len(set(names)) != len(names):
            raise DataFormatError(f"model: an effect appears twice in {names}")
        for e in effects:
            node = e.params.get("node")
            if node is not None and int(node) >= self.ladder.order:
                raise DataFormatError(f"effect {e.name}: node {int(node)} does not exist in a "
                                      f"{self.ladder.order}-stage ladder")
        if self.electrical is not None and not isinstance(self.electrical, DiodeLaw):
            raise DataFormatError("model: electrical must be a DiodeLaw")
        object.__setattr__(self, "effects", effects)
        object.__setattr__(self, "provenance", MappingProxyType(dict(self.provenance)))

    # -- views ---------------------------------------------------------------------------
    @property
    def rth(self) -> float:
        return self.ladder.rth

    @property
    def device_effects(self) -> tuple[Effect, ...]:
        return tuple(e for e in self.effects if e.kind == DEVICE)

    @property
    def is_linear(self) -> bool:
        """True when no device effect is present (closed-form solutions apply)."""
        return not self.device_effects

    def effect(self, name: str) -> Effect | None:
        return next((e for e in self.effects if e.name == name), None)

    def with_effects(self, effects: Sequence[Effect]) -> ThermalModel:
        return replace(self, effects=tuple(effects))

    def with_topology(self, topology: str) -> ThermalModel:
        """The same model with its ladder converted (exactly) to ``foster`` or ``cauer``."""
        if topology == self.ladder.topology:
            return self
        if topology == "foster":
            ladder: Foster | Cauer = self.ladder.to_foster()  # type: ignore[union-attr]
        elif topology == "cauer":
            ladder = self.ladder.to_cauer()  # type: ignore[union-attr]
        else:
            raise DataFormatError(f"topology {topology!r}: expected foster or cauer")
        return replace(self, ladder=ladder)

    # -- nonlinear network ----------------------------------------------------------------
    def network(self) -> Network:
        """The nodal network simulated: the ladder's own for a linear model, its exact Cauer
        form with device effects (the effects' physics is written on physical layers)."""
        if self.is_linear:
            return Network.of(self.ladder)
        return Network.of(as_cauer(self.ladder))

    def batch(self) -> NetworkBatch:
        """The model as a batch of one of the network simulator
        (:class:`~spicethermal.engines.network.NetworkBatch`): its Cauer form and device
        effects."""
        return NetworkBatch.of(self.ladder, self.device_effects)

    def _matrices(self, theta: NDArray, tref_c: float, net: Network) -> tuple[NDArray, NDArray]:
        """``(Cm(θ), G(θ))`` of the network at node rises ``θ``: each layer's resistance scaled
        by the device effects, each node's capacity plus the effects' (the tangent of the heat
        they store)."""
        if self.is_linear:
            return net.capacitance(), net.conductance()
        batch = self.batch()
        x = np.asarray(theta, dtype=float)[None, :]
        scale = batch.scale(x, tref_c)[0]
        cap = batch.c[0] + batch.stored(tref_c + x)[1][0]
        if np.any(cap <= 0):
            raise SimulationError("a heat capacity falls to zero or below (capacity slope "
                                  "too steep for the temperatures reached)")
        return np.diag(cap), net.conductance(scale)

    def _integrate(self, net: Network, theta0: NDArray,
                   segments: Sequence[tuple[float, float, float]], tref_c: float,
                   t_eval: NDArray | None = None, rtol: float = 1e-9,
                   atol: float = 1e-10) -> tuple[NDArray, list[NDArray]]:
        """Integrate piece by piece with the network simulator (a step's tolerance, a
        fraction of the largest rise, follows ``rtol``: its default tolerance for a loose
        ``rtol``, a tenth of it at the tightest); returns the end state and (t, θ) rows at
        ``t_eval``."""
        batch = self.batch()
        batch.tol_rel = min(TOL_REL, max(rtol * 1e3, TOL_REL / 10))
        theta = np.asarray(theta0, dtype=float)
        rows: list[NDArray] = []
        for t0, t1, p in segments:
            ev = np.empty(0) if t_eval is None else t_eval[(t_eval >= t0) & (t_eval <= t1)]
            times = np.append(ev - t0, t1 - t0)
            states = batch.response(theta[None, :], times, p, tref_c)[0]
            if not np.all(np.isfinite(states)):
                raise SimulationError(f"nonlinear integration failed after t = {t0:g} s")
            if ev.size:
                rows.append(np.column_stack([ev, states[:-1]]))
            theta = states[-1]
        return theta, rows

    # -- simulation ----------------------------------------------------------------------
    def simulate(self, t_s: ArrayLike, schedule: Schedule, tref_c: float = 25.0,
                 theta0: ArrayLike | None = None) -> Trajectory:
        """Node rises at times ``t_s`` under a piecewise-constant power ``schedule``.

        Starts from ``theta0`` (node rises of :meth:`network`, default 0: the model at the
        reference temperature).

        Examples
        --------
        >>> m = ThermalModel(Foster.from_tau([2.0], [1.0]))
        >>> tr = m.simulate([1.0], Schedule.step(1.0))
        >>> bool(round(float(tr.tj_k[0]), 9) == round(2 * (1 - np.exp(-1)), 9))
        True
        """
        t = np.asarray(t_s, dtype=float).ravel()
        if t.size == 0 or not np.all(np.isfinite(t)) or np.any(t < 0) or np.any(np.diff(t) < 0):
            raise DataFormatError("simulate: times must be finite, non-negative and ascending")
        net = self.network()
        x0 = np.zeros(net.n) if theta0 is None else np.asarray(theta0, dtype=float)
        if self.is_linear:
            return Trajectory(t, linear_response(net, x0, schedule, t))
        segs = schedule.segments(float(t[-1]))
        _, pieces = self._integrate(net, x0, segs, tref_c, t_eval=t)
        rows = np.vstack(pieces) if pieces else np.empty((0, net.n + 1))
        _, idx = np.unique(rows[:, 0], return_index=True)  # a shared edge appears twice
        theta = rows[idx, 1:] if rows.size else np.tile(x0, (t.size, 1))
        return Trajectory(t, theta)

    def steady_nodes(self, power_w: float, tref_c: float = 25.0) -> NDArray:
        """Node rises of :meth:`network` under constant ``power_w`` (solved self-consistently
        with the effects)."""
        net = self.network()
        if self.is_linear:
            b = np.zeros(net.n)
            b[0] = power_w
            return np.linalg.solve(net.conductance(), b)
        theta = self.batch().steady(power_w, tref_c)[0]
        if not np.all(np.isfinite(theta)):
            raise SimulationError(f"steady state at {power_w:g} W did not converge; is the "
                                  f"temperature coefficient strong enough for thermal runaway?")
        return theta

    def pwm(self, power_w: float, freq_hz: float, duty: float, window_s: float = 0.0,
            tref_c: float = 25.0, tol_k: float = 1e-6) -> PwmState:
        """Periodic steady state under PWM (closed form if linear, shooting otherwise)."""
        if self.is_linear:
            return steady_state(self.ladder, power_w, freq_hz, duty, window_s)
        check_drive(freq_hz, duty, power_w, window_s)
        valley, peak, reading = self._periodic(power_w, freq_hz, duty, window_s, tref_c, tol_k)
        period = 1 / freq_hz
        t = np.linspace(0, period, 401)
        tr = self.simulate(t, Schedule.pwm(power_w, freq_hz, duty, 1), tref_c, valley)
        mean = float(np.trapezoid(tr.tj_k, t) / period)
        return PwmState(float(freq_hz), float(duty), float(power_w), float(window_s),
                        float(peak[0]), mean, float(valley[0]), float(reading[0]))

    def pwm_reading(self, power_w: float, freq_hz: float, duty: float, window_s: float = 0.0,
                    tref_c: float = 25.0, tol_k: float = 1e-6) -> float:
        """The junction's rise (K) read ``window_s`` after an on-phase ends in the PWM periodic
        steady state: :meth:`pwm`'s ``reading_k`` without the period's mean (one integration
        of a period fewer).

        >>> m = ThermalModel(Foster.from_tau([100.0], [1.0]))
        >>> m.pwm_reading(0.1, 1e3, 0.5, 1e-4) == m.pwm(0.1, 1e3, 0.5, 1e-4).reading_k
        True
        """
        if self.is_linear:
            return self.pwm(power_w, freq_hz, duty, window_s).reading_k
        check_drive(freq_hz, duty, power_w, window_s)
        return float(self._periodic(power_w, freq_hz, duty, window_s, tref_c, tol_k)[2][0])

    def _periodic(self, power_w: float, freq_hz: float, duty: float, window_s: float,
                  tref_c: float, tol_k: float) -> tuple[NDArray, NDArray, NDArray]:
        """Node rises of the periodic steady state (nonlinear model): at the start of an
        on-phase, at its end, and ``window_s`` after it."""
        valley, net = self.pwm_initial_state(power_w, freq_hz, duty, tref_c, tol_k), self.network()
        peak, _ = self._integrate(net, valley, [(0.0, duty / freq_hz, power_w)], tref_c)
        reading = peak
        if window_s > 0:
            reading, _ = self._integrate(net, peak, [(0.0, window_s, 0.0)], tref_c)
        return valley, peak, reading

    def pwm_initial_state(self, power_w: float, freq_hz: float, duty: float,
                          tref_c: float = 25.0, tol_k: float = 1e-6,
                          max_iter: int = 50) -> NDArray:
        """Node rises at the start of an on-phase in the periodic steady state.

        Closed form for a linear model. With device effects: shooting, a chord-Newton
        iteration on the one-period map whose Jacobian is the period map of the network frozen
        at the current state; it starts from the closed-form periodic state of the network
        frozen at the self-consistent mean (exact to first order in the nonlinearity, so one
        iteration is usually enough). The period is integrated at a tolerance matched to
        ``tol_k`` (the largest accepted change of the state over one period, K).

        Parameters
        ----------
        power_w, freq_hz, duty : float
            Pulse power (W), PWM frequency (Hz) and duty cycle (0..1).
        tref_c : float
            Reference temperature, degC (matters for device effects).
        tol_k : float
            Accepted periodicity error, K.
        max_iter : int
            Shooting iterations before :class:`SimulationError`.

        Returns
        -------
        NDArray
            Node rises over the reference (K), junction first.

        Examples
        --------
        >>> m = ThermalModel(Foster.from_tau([10.0], [1e-3]))
        >>> x = m.pwm_initial_state(0.1, 1e3, 0.5)  # valley: P R (1 - e^-½) e^-½ / (1 - e^-1)
        >>> bool(abs(x[0] - (1 - np.exp(-0.5)) * np.exp(-0.5) / -np.expm1(-1.0)) < 1e-12)
        True
        """
        check_drive(freq_hz, duty, power_w)
        net = self.network()
        period = 1 / freq_hz
        if self.is_linear:
            return _FrozenPeriod(net.capacitance(), net.conductance(), period).start(
                power_w, duty)
        segs = [s for s in ((0.0, duty * period, power_w), (duty * period, period, 0.0))
                if s[1] > s[0]]
        x = self.steady_nodes(power_w * duty, tref_c)
        # the frozen network's periodic state: its period average is the mean state x itself
        x = _FrozenPeriod(*self._matrices(x, tref_c, net), period).start(power_w, duty)
        for _ in range(max_iter):
            end, _ = self._integrate(net, x, segs, tref_c, rtol=max(1e-9, 1e-3 * tol_k),
                                     atol=max(1e-10, 1e-4 * tol_k))
            r = end - x
            if np.max(np.abs(r)) < tol_k:
                return end
            x = x + _FrozenPeriod(*self._matrices(x, tref_c, net), period).solve(r)
        raise SimulationError(f"PWM shooting did not converge at {freq_hz:g} Hz, duty {duty:g}")

    # -- files ---------------------------------------------------------------------------
    def to_dict(self) -> dict:
        """The ``spicethermal-model/3`` document, ``/4`` with an ``electrical`` law
        (docs/model-format.md, schema in ``spicethermal/data/model.schema.json``).

        >>> d = ThermalModel(Cauer([1.0, 2.0], [0.0, 3.0]), reference="case").to_dict()
        >>> d["format"], d["stages"][0], d["reference"]
        ('spicethermal-model/3', {'r_k_per_w': 1.0, 'c_j_per_k': 0.0}, 'case')
        """
        out = {
            "format": MODEL_FORMAT if self.electrical is None else MODEL_FORMAT_ELECTRICAL,
            "topology": self.ladder.topology,
            "stages": [{"r_k_per_w": r, "c_j_per_k": c}
                       for r, c in zip(self.ladder.r, self.ladder.c, strict=True)],
            "rth_k_per_w": self.rth,
            "reference": self.reference,
            "effects": [e.to_dict() for e in self.effects],
            "provenance": _jsonable(self.provenance),
        }
        if self.case_c_j_per_k:
            out["case_c_j_per_k"] = self.case_c_j_per_k
        if self.electrical is not None:
            out["electrical"] = self.electrical.to_dict()
        return out

    @classmethod
    def from_dict(cls, data: Mapping, source: str = "model") -> ThermalModel:
        """Read a ``spicethermal-model/3`` (or ``/2``, ``/1``) document; errors name ``source``
        and the key. An older file whose Foster ladder holds a ``phase-change`` band away from
        the junction is refused: its band sat at an inner node of the Foster network, which
        no physical layer matches, where ``/3`` places it at that layer of the Cauer form.

        >>> m = ThermalModel.from_dict({"format": "spicethermal-model/1", "topology": "foster",
        ...     "stages": [{"r_k_per_w": 2.0, "c_j_per_k": 0.5}]})
        >>> m.rth, m.reference
        (2.0, 'ambient')
        """
        if not isinstance(data, Mapping):
            raise DataFormatError(f"{source}: not a JSON object")
        if data.get("format") not in MODEL_FORMATS_READ:
            raise DataFormatError(f"{source}: format {data.get('format')!r} is not one of "
                                  f"{', '.join(MODEL_FORMATS_READ)}")
        topology = data.get("topology")
        kinds = {"foster": Foster, "cauer": Cauer}
        if not isinstance(topology, str) or topology not in kinds:
            raise DataFormatError(f"{source}: topology {topology!r} must be foster or cauer")
        stages = data.get("stages")
        if not isinstance(stages, list) or not stages:
            raise DataFormatError(f"{source}: 'stages' must be a non-empty list")
        try:
            r = [float(s["r_k_per_w"]) for s in stages]
            c = [float(s["c_j_per_k"]) for s in stages]
        except (KeyError, TypeError, ValueError) as exc:
            raise DataFormatError(f"{source}: every stage needs numeric r_k_per_w and c_j_per_k "
                                  f"({exc})") from None
        try:
            ladder = kinds[topology](r, c)
        except DataFormatError as exc:
            raise DataFormatError(f"{source}: {exc}") from None
        effects = data.get("effects", [])
        if not isinstance(effects, list):
            raise DataFormatError(f"{source}: 'effects' must be a list")
        case_c = data.get("case_c_j_per_k", 0.0)
        if isinstance(case_c, bool) or not isinstance(case_c, int | float):
            raise DataFormatError(f"{source}: case_c_j_per_k must be a number")
        provenance = data.get("provenance", {}) or {}
        if not isinstance(provenance, Mapping):
            raise DataFormatError(f"{source}: 'provenance' must be an object")
        electrical = None
        if data.get("electrical") is not None:
            if data["format"] != MODEL_FORMAT_ELECTRICAL:
                raise DataFormatError(f"{source}, key electrical: a diode law needs format "
                                      f"{MODEL_FORMAT_ELECTRICAL!r}")
            electrical = DiodeLaw.from_dict(data["electrical"], source)
        try:
            model = cls(ladder, tuple(Effect.from_dict(e) for e in effects),
                        data.get("reference", "ambient"), provenance, float(case_c), electrical)
        except DataFormatError as exc:
            raise DataFormatError(f"{source}: {exc}") from None
        placed = next((e for e in model.effects if e.physical_nodes and "node" in e.params),
                      None)
        if placed is not None and topology == "foster" and data["format"] in \
                MODEL_FORMATS_READ[:2]:
            raise DataFormatError(
                f"{source}: {data['format']} puts the {placed.name} at node "
                f"{int(placed.params['node'])} of the Foster network, which is no physical "
                f"layer ({MODEL_FORMAT} puts it at that layer of the Cauer form): fit the model "
                f"again")
        return model

    def save(self, path: str | Path) -> Path:
        """Write the ``spicethermal-model/3`` (``/4`` with a diode law) JSON file atomically."""
        return atomic_write_text(path, dumps_json(self.to_dict(), indent=2) + "\n")

    @classmethod
    def load(cls, path: str | Path) -> ThermalModel:
        """Read a ``spicethermal-model/4`` (or ``/3``, ``/2``, ``/1``) JSON file."""
        return cls.from_dict(read_json(path), str(path))


class _FrozenPeriod:
    """The one-period map of the linear network ``Cm dθ/dt = e0 P(t) − G θ`` in modal form.

    ``G v = λ Cm v`` with ``vᵀ Cm v = I``: ``θ = V z``, ``dz/dt = −λ z + V[0] P``; over a period
    ``z → a z + c`` with ``a = exp(−λ T)``.
    """

    def __init__(self, cm: NDArray, g: NDArray, period_s: float) -> None:
        from scipy.linalg import eigh

        self.lam, self.v = eigh(g, cm)
        self.vinv = self.v.T @ cm
        self.period = period_s

    def start(self, power_w: float, duty: float) -> NDArray:
        """State at the start of an on-phase in the periodic steady state."""
        lam, t = self.lam, self.period
        c = power_w * self.v[0] / lam * -np.expm1(-lam * duty * t)  # after the on-phase
        c = c * np.exp(-lam * (1 - duty) * t)  # and the off-phase, from z = 0
        return self.v @ (c / -np.expm1(-lam * t))

    def solve(self, r: NDArray) -> NDArray:
        """``(I − A)⁻¹ r`` with ``A`` the period map's Jacobian."""
        return self.v @ ((self.vinv @ r) / -np.expm1(-self.lam * self.period))


def _jsonable(obj):
    if isinstance(obj, Mapping):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    return obj
