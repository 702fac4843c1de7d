"""Temperature laws of the independent network: how a layer's resistance and a node's latent
heat follow temperature (independent of :mod:`spicethermal.effects`).

:class:`ResistanceLaw` gives ``R(T)/R0`` and its slope for the catalogue's forms (linear, power
law in kelvin) and for forms that are in no catalogue: exponential, quadratic, saturating, a
conductivity with a minimum (a resistance with a maximum), and a convection that switches
regime. :class:`LatentHeat` gives the extra heat capacity of a band of latent heat: gaussian,
logistic, plateau or skewed (a sharp upper edge and a long tail below, as an impure material
melts), optionally with hysteresis (melting around ``t_c``, solidifying ``gap_k`` lower).

>>> round(ResistanceLaw("exp", alpha_per_k=0.01).factor(125.0), 4)
2.7183
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["KELVIN", "LAW_KINDS", "SHAPES", "LatentHeat", "ResistanceLaw"]

KELVIN = 273.15
SHAPES = ("gaussian", "logistic", "plateau", "skewed")
LAW_KINDS = ("linear", "power", "switch", "exp", "quadratic", "saturating", "kmin")
#: Share of its liquid fraction over which the cooling branch of a partly molten band switches
#: on.
CAP_SOFTNESS = 0.01


def _sigmoid(z: float) -> float:
    return 0.5 * (1.0 + math.tanh(0.5 * z))


def _softplus(z: float) -> float:
    return max(z, 0.0) + math.log1p(math.exp(-abs(z)))


@dataclass(frozen=True)
class ResistanceLaw:
    """How a layer's resistance follows temperature, ``R(T)/R0`` with ``u = T − t0_c``:

    * ``"linear"``: ``1 + alpha_per_k·u`` (clipped at 0.05);
    * ``"power"``: ``((T + 273.15)/(t0_c + 273.15))^exponent`` (conductivity ``∝ T^−n``);
    * ``"switch"``: ``1 − drop·σ(u/width_k)``, a smooth step down around ``t0_c`` (convection
      changing regime);
    * ``"exp"``: ``exp(alpha_per_k·u)``;
    * ``"quadratic"``: ``1 + alpha_per_k·u + beta_per_k2·u²`` (clipped at 0.05);
    * ``"saturating"``: ``1 + amp·tanh(u/width_k)``;
    * ``"kmin"``: ``(1 + beta_per_k2 (t0_c − t1_c)²)/(1 + beta_per_k2 (T − t1_c)²)``, a
      conductivity with a minimum at ``t1_c`` (the resistance peaks there).

    >>> ResistanceLaw("power", exponent=1.0).factor(25.0 + 298.15)
    2.0
    >>> round(ResistanceLaw("kmin", beta_per_k2=1e-3, t1_c=45.0).factor(45.0), 6)
    1.4
    """

    kind: str = "linear"
    alpha_per_k: float = 0.0
    exponent: float = 0.0
    t0_c: float = 25.0
    drop: float = 0.0
    width_k: float = 1.0
    beta_per_k2: float = 0.0
    amp: float = 0.0
    t1_c: float = 25.0

    def __post_init__(self) -> None:
        if self.kind not in LAW_KINDS:
            raise ValueError(f"resistance law {self.kind!r}: expected one of {LAW_KINDS}")

    def factor(self, t_c: float) -> float:
        """``R(T)/R0``."""
        u = t_c - self.t0_c
        if self.kind == "switch":
            return 1.0 - self.drop * _sigmoid(u / self.width_k)
        if self.kind == "power":
            return ((t_c + KELVIN) / (self.t0_c + KELVIN)) ** self.exponent
        if self.kind == "exp":
            return math.exp(self.alpha_per_k * u)
        if self.kind == "saturating":
            return 1.0 + self.amp * math.tanh(u / self.width_k)
        if self.kind == "kmin":
            b, v = self.beta_per_k2, t_c - self.t1_c
            return (1.0 + b * (self.t0_c - self.t1_c) ** 2) / (1.0 + b * v * v)
        quad = self.beta_per_k2 * u * u if self.kind == "quadratic" else 0.0
        return max(0.05, 1.0 + self.alpha_per_k * u + quad)

    def slope(self, t_c: float) -> float:
        """``d(R/R0)/dT`` (1/K)."""
        u = t_c - self.t0_c
        if self.kind == "switch":
            sig = _sigmoid(u / self.width_k)
            return -self.drop * sig * (1.0 - sig) / self.width_k
        if self.kind == "power":
            x = (t_c + KELVIN) / (self.t0_c + KELVIN)
            return self.exponent * x ** (self.exponent - 1.0) / (self.t0_c + KELVIN)
        if self.kind == "exp":
            return self.alpha_per_k * math.exp(self.alpha_per_k * u)
        if self.kind == "saturating":
            return self.amp / self.width_k / math.cosh(u / self.width_k) ** 2
        if self.kind == "kmin":
            b, v = self.beta_per_k2, t_c - self.t1_c
            return -self.factor(t_c) * 2.0 * b * v / (1.0 + b * v * v)
        quad = self.beta_per_k2 if self.kind == "quadratic" else 0.0
        if 1.0 + self.alpha_per_k * u + quad * u * u <= 0.05:
            return 0.0
        return self.alpha_per_k + 2.0 * quad * u


@dataclass(frozen=True)
class LatentHeat:
    """Latent heat ``latent_j`` absorbed at ``node`` over a band centred at ``t_c``.

    ``width_k`` is the standard deviation for ``"gaussian"`` and ``"logistic"`` bands, the full
    width for a ``"plateau"`` (flat top, logistic edges of ``width_k/10``) and the scale of a
    ``"skewed"`` band (a mirrored Gumbel density: its mode at ``t_c``, a sharp upper edge and a
    long tail below).

    Hysteresis: with ``gap_k > 0`` the band melts around ``t_c`` on the way up and solidifies
    around ``t_c − gap_k`` on the way down (:meth:`cooling_branch`). ``liquid`` < 1 is a
    cooling branch that starts partly molten: only the liquid fraction solidifies, the band's
    capacity switching on where the solidified fraction reaches it.

    >>> from scipy.integrate import quad
    >>> h = LatentHeat(0, 0.5, 60.0, 2.0, "plateau")
    >>> round(quad(h.capacity, 40, 80, points=[59, 61])[0], 6)
    0.5
    >>> round(h.fraction(80.0), 9)
    1.0
    """

    node: int
    latent_j: float
    t_c: float
    width_k: float
    shape: str = "gaussian"
    gap_k: float = 0.0
    liquid: float = 1.0

    def __post_init__(self) -> None:
        if self.shape not in SHAPES:
            raise ValueError(f"latent heat shape {self.shape!r}: expected one of {SHAPES}")

    def _edges(self) -> list[tuple[float, float, float]]:
        """(sign, centre, logistic scale) of the logistic edges of a plateau band."""
        e = self.width_k / 10.0
        return [(1.0, self.t_c - self.width_k / 2, e), (-1.0, self.t_c + self.width_k / 2, e)]

    def fraction(self, t_c: float) -> float:
        """Share of the band below ``t_c`` (the molten fraction on the way up)."""
        z = (t_c - self.t_c) / self.width_k
        if self.shape == "gaussian":
            return 0.5 * (1.0 + math.erf(z / math.sqrt(2.0)))
        if self.shape == "logistic":
            return _sigmoid(z * math.pi / math.sqrt(3.0))
        if self.shape == "skewed":
            return -math.expm1(-math.exp(min(z, 50.0)))
        (_, c1, e), (_, c2, _) = self._edges()
        return e / self.width_k * (_softplus((t_c - c1) / e) - _softplus((t_c - c2) / e))

    def _density(self, t_c: float) -> tuple[float, float]:
        """The band's capacity (J/K) and its slope (J/K²), all of it molten."""
        lat, w = self.latent_j, self.width_k
        if self.shape == "gaussian":
            z = (t_c - self.t_c) / w
            f = lat * math.exp(-0.5 * z * z) / (w * math.sqrt(2 * math.pi))
            return f, -f * (t_c - self.t_c) / w ** 2
        if self.shape == "logistic":
            s = w * math.sqrt(3.0) / math.pi
            sig = _sigmoid((t_c - self.t_c) / s)
            return lat * sig * (1.0 - sig) / s, lat * sig * (1.0 - sig) * (1.0 - 2.0 * sig) / s ** 2
        if self.shape == "skewed":
            z = min((t_c - self.t_c) / w, 50.0)
            ez = math.exp(z)
            f = lat * math.exp(z - ez) / w
            return f, f * (1.0 - ez) / w
        f = lat / w * sum(sign * _sigmoid((t_c - c) / e) for sign, c, e in self._edges())
        total = 0.0
        for sign, c, e in self._edges():
            sig = _sigmoid((t_c - c) / e)
            total += sign * sig * (1.0 - sig) / e
        return f, lat / w * total

    def capacity(self, t_c: float) -> float:
        """Extra heat capacity (J/K) at temperature ``t_c``."""
        f, _ = self._density(t_c)
        return f if self.liquid >= 1.0 else f * self._gate(t_c)

    def capacity_slope(self, t_c: float) -> float:
        """``d capacity / dT`` (J/K²)."""
        f, df = self._density(t_c)
        if self.liquid >= 1.0:
            return df
        if self.liquid <= 0.0:
            return 0.0
        s = self._gate(t_c)
        ds = -s * (1.0 - s) * f / self.latent_j / (CAP_SOFTNESS * self.liquid)
        return df * s + f * ds

    def _gate(self, t_c: float) -> float:
        """1 where the band's share below ``t_c`` is under the liquid fraction (the cooling
        front has reached the liquid), switching over a share of :data:`CAP_SOFTNESS` of
        that fraction."""
        if self.liquid <= 0.0:
            return 0.0
        return _sigmoid((self.liquid - self.fraction(t_c)) / (CAP_SOFTNESS * self.liquid))

    def cooling_branch(self, start_c: float) -> LatentHeat:
        """The band as it acts on a cooling from ``start_c`` (reached by heating from below):
        centred ``gap_k`` lower, with the liquid fraction molten on the way up. Without
        hysteresis, the band itself."""
        if self.gap_k <= 0.0:
            return self
        liquid = self.fraction(start_c)
        return LatentHeat(self.node, self.latent_j, self.t_c - self.gap_k, self.width_k,
                          self.shape, 0.0, 1.0 if liquid > 1.0 - 1e-6 else liquid)
