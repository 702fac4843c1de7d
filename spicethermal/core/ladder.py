"""RC ladders: the Foster and Cauer thermal networks, and exact conversion between them.

Electrical analogy: heat flow (W) is a current, temperature rise (K) a voltage, thermal
resistance (K/W) a resistance, heat capacity (J/K) a capacitance.

* :class:`Foster` — parallel RC stages in series. Its impedance is
  ``Z(s) = sum r_i / (1 + s tau_i)``: the form a fitted Zth(t) comes in. Its inner nodes are
  not physical temperatures.
* :class:`Cauer` — capacitors to the reference, resistors in a chain from the junction. Its
  nodes are physical (die, solder, case, ...), which is the form to couple to other networks.

Both conversions go through the bidiagonal factor of the Cauer network
(:mod:`spicethermal.core.bidiagonal`): the ladder's conductance matrix is ``G = Aᵀ R⁻¹ A`` with
``A`` bidiagonal, so its modes are the squared singular values of ``B = R^-1/2 A C^-1/2``. Cauer ->
Foster is LAPACK's bidiagonal SVD (high relative accuracy in double precision, O(n²): 0.04 s at
1000 stages). Foster -> Cauer is the inverse problem, ill-conditioned by nature: exact rational
arithmetic up to :data:`RATIONAL_MAX_ORDER` stages, above that Golub–Kahan bidiagonalisation in
double precision, accepted only if converting back reproduces every R and τ within
:data:`ROUND_TRIP_RTOL`; otherwise the Lanczos recursion in checked extended precision (up to
:data:`EXTENDED_MAX_ORDER` stages), else a one-line refusal.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from .bidiagonal import bidiagonalize, singular_values
from .errors import DataFormatError

#: Largest order :meth:`Foster.to_cauer` converts by exact rational arithmetic (auto method).
RATIONAL_MAX_ORDER = 12
#: Largest relative error in any R or τ a Foster -> Cauer conversion may show when converted back.
ROUND_TRIP_RTOL = 1e-9
#: Largest order converted in extended precision when double precision is not enough.
EXTENDED_MAX_ORDER = 100
#: A Foster stage whose R is below this fraction of the median R is dead (:meth:`Foster.pruned`).
DEAD_STAGE = 1e-9

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray


def _validated(name: str, values: ArrayLike, n: int | None = None,
               allow_zero: bool = False) -> tuple[float, ...]:
    arr = np.asarray(values, dtype=float).ravel()
    if arr.size == 0:
        raise DataFormatError(f"{name}: a ladder needs at least one stage")
    if n is not None and arr.size != n:
        raise DataFormatError(f"{name}: expected {n} values, got {arr.size}")
    values = arr.tolist()  # Python floats: a ladder is built for every PWM row of a fit
    for i, v in enumerate(values):
        if not math.isfinite(v) or v < 0 or (v == 0 and not allow_zero):
            raise DataFormatError(f"{name}[{i}] = {v!r}: must be "
                                  f"{'non-negative' if allow_zero else 'positive'} and finite")
    return tuple(values)


@dataclass(frozen=True, init=False)
class _Ladder:
    """Common part of both networks: stage resistances (K/W) and capacitances (J/K)."""

    r: tuple[float, ...]
    c: tuple[float, ...]

    def __init__(self, r: ArrayLike, c: ArrayLike) -> None:
        rr = _validated("r_k_per_w", r)
        object.__setattr__(self, "r", rr)
        object.__setattr__(self, "c", _validated("c_j_per_k", c, len(rr)))

    topology: ClassVar[str] = ""

    @property
    def order(self) -> int:
        """Number of RC stages."""
        return len(self.r)

    @property
    def rth(self) -> float:
        """Total (steady-state) thermal resistance, K/W."""
        return float(sum(self.r))

    def __len__(self) -> int:
        return self.order

    # -- responses, all through the Foster form -------------------------------------------
    def _foster(self) -> Foster:
        raise NotImplementedError

    def zth(self, t: ArrayLike) -> NDArray:
        """Step response Zth(t) in K/W: temperature rise per watt after power is switched on."""
        f = self._foster()
        t = np.asarray(t, dtype=float)
        tau = np.asarray(f.tau)
        return (np.asarray(f.r) * -np.expm1(-t[..., None] / tau)).sum(axis=-1)

    def cooling(self, t: ArrayLike) -> NDArray:
        """Cooling curve in K/W: rise per watt at time t after power is cut from steady state."""
        f = self._foster()
        t = np.asarray(t, dtype=float)
        return (np.asarray(f.r) * np.exp(-t[..., None] / np.asarray(f.tau))).sum(axis=-1)

    def r_norm(self, t: ArrayLike) -> NDArray:
        """Normalized thermal impedance r(t) = Zth(t) / Rth (eq. 2 of the paper)."""
        return self.zth(t) / self.rth

    def impedance(self, omega: ArrayLike) -> NDArray:
        """Complex thermal impedance Z(jω) in K/W at angular frequencies ``omega`` (rad/s)."""
        f = self._foster()
        w = np.asarray(omega, dtype=float)
        return (np.asarray(f.r) / (1 + 1j * w[..., None] * np.asarray(f.tau))).sum(axis=-1)

    def time_constants(self) -> NDArray:
        """Time constants of the network (its poles, -1/s), ascending, in seconds."""
        return np.sort(np.asarray(self._foster().tau))

    def step(self, power_w: float, t: ArrayLike) -> NDArray:
        """Temperature rise (K) under a power step of ``power_w`` from t = 0."""
        return power_w * self.zth(t)


@dataclass(frozen=True, init=False)
class Foster(_Ladder):
    """Foster network: stages ``r_i || c_i`` in series, ``Z(s) = Σ r_i / (1 + s r_i c_i)``.

    Stages are kept sorted by time constant, fastest first.

    Attributes
    ----------
    r : tuple of float
        Stage resistances (K/W), fastest stage first.
    c : tuple of float
        Stage capacitances (J/K), in the same order.

    >>> f = Foster.from_tau([1.0, 2.0], [1e-3, 1.0])
    >>> f.rth
    3.0
    >>> round(float(f.zth(1e9)), 12)
    3.0
    """

    topology: ClassVar[str] = "foster"

    def __init__(self, r: ArrayLike, c: ArrayLike) -> None:
        rr = np.asarray(_validated("r_k_per_w", r))
        cc = np.asarray(_validated("c_j_per_k", c, rr.size))
        order = np.argsort(rr * cc, kind="stable")
        super().__init__(rr[order], cc[order])

    @classmethod
    def from_tau(cls, r: ArrayLike, tau: ArrayLike) -> Foster:
        """Build from resistances (K/W) and time constants (s), as datasheets publish them."""
        rr = np.asarray(_validated("r_k_per_w", r))
        tt = np.asarray(_validated("tau_s", tau, rr.size))
        return cls(rr, tt / rr)

    @classmethod
    def from_cauer(cls, cauer: Cauer) -> Foster:
        """Exact conversion of a Cauer network (bidiagonal SVD, high relative accuracy)."""
        return cauer.to_foster()

    @property
    def tau(self) -> tuple[float, ...]:
        """Stage time constants ``r_i c_i`` in seconds, ascending."""
        return tuple(r * c for r, c in zip(self.r, self.c, strict=True))

    def _foster(self) -> Foster:
        return self

    def pruned(self, rel: float = DEAD_STAGE) -> Foster:
        """This ladder without its dead stages, those whose R is below ``rel`` × the median R
        (a fit can drive a stage's R to nothing: the responses hardly change, but its Cauer
        form becomes ill-conditioned); itself when none is dead.

        >>> Foster.from_tau([1.0, 1e-300, 2.0], [1.0, 9.0, 3.0]).pruned().order
        2
        """
        r = np.asarray(self.r)
        live = r >= rel * float(np.median(r))  # the median stage always lives
        return self if live.all() else Foster(r[live], np.asarray(self.c)[live])

    def to_cauer(self, method: str = "auto") -> Cauer:
        """Exact Foster -> Cauer conversion.

        ``rational``: the continued fraction in exact rational arithmetic (slow beyond
        ~15 stages: 2 s at order 20, a minute at 40). ``bidiagonal``: Golub–Kahan
        bidiagonalisation in double precision (0.005 s at 200 stages, 0.2 s at 1000).
        ``lanczos``: the Lanczos (Stieltjes) tridiagonalisation of the spectral measure in
        extended precision, checked against the Foster impedance at every pole and redone with
        more digits if it is off by more than 1e-9. ``auto``: rational up to
        :data:`RATIONAL_MAX_ORDER` stages; above, bidiagonal if converting the result back
        reproduces every R and τ within :data:`ROUND_TRIP_RTOL`, else Lanczos up to
        :data:`EXTENDED_MAX_ORDER` stages, else :class:`DataFormatError`.

        >>> f = Foster.from_tau([1.0, 2.0, 3.0], [1e-3, 1e-1, 10.0])
        >>> a, b = f.to_cauer("bidiagonal"), f.to_cauer("rational")
        >>> bool(np.allclose(a.r + a.c, b.r + b.c, rtol=1e-12, atol=0))
        True
        """
        if method == "rational" or (method == "auto" and self.order <= RATIONAL_MAX_ORDER):
            return Cauer(*_foster_to_cauer(self.r, self.tau))
        if method == "bidiagonal":
            return _foster_to_cauer_bidiagonal(self)
        if method == "lanczos":
            return _foster_to_cauer_lanczos(self)
        if method != "auto":
            raise DataFormatError(f"method {method!r}: expected auto, rational, bidiagonal or "
                                  f"lanczos")
        try:
            cauer = _foster_to_cauer_bidiagonal(self)
            error = round_trip_error(self, cauer)
        except (ArithmeticError, DataFormatError):
            error = math.inf
        if error <= ROUND_TRIP_RTOL:
            return cauer
        if self.order > EXTENDED_MAX_ORDER:
            got = f"only to {error:.1e}" if math.isfinite(error) else "not at all"
            raise DataFormatError(
                f"Foster -> Cauer at order {self.order}: double precision reproduces the ladder "
                f"{got} (limit {ROUND_TRIP_RTOL:g}) and extended precision is limited to "
                f"{EXTENDED_MAX_ORDER} stages: lump it to fewer stages")
        return _foster_to_cauer_lanczos(self)


@dataclass(frozen=True, init=False)
class Cauer(_Ladder):
    """Cauer network: ``c_i`` from node i to the thermal ground, ``r_i`` from node i to node i+1.

    Node 0 is the junction; the last resistor ends at the reference. A capacitance may be zero
    (a node without heat capacity, as some vendors' ladders have), but not all of them.

    Attributes
    ----------
    r : tuple of float
        Resistances (K/W): ``r[i]`` from node i to node i+1 (the last one to the reference).
    c : tuple of float
        Capacitances (J/K): ``c[i]`` from node i to the thermal ground.

    >>> c = Foster.from_tau([1.0], [2.0]).to_cauer()
    >>> c.r, c.c
    ((1.0,), (2.0,))
    """

    topology: ClassVar[str] = "cauer"

    def __init__(self, r: ArrayLike, c: ArrayLike) -> None:
        rr = _validated("r_k_per_w", r)
        cc = _validated("c_j_per_k", c, len(rr), allow_zero=True)
        if not any(cc):
            raise DataFormatError("c_j_per_k: a Cauer ladder needs a non-zero capacitance")
        object.__setattr__(self, "r", rr)
        object.__setattr__(self, "c", cc)

    def with_capacitances(self) -> Cauer:
        """The same ladder without zero capacitances (itself when it has none).

        A node without capacity inside the ladder joins its two resistors in series (exact).
        One at the junction is a resistance that responds at once; it gets a capacitance whose
        time constant is 1e-12 of the ladder's fastest ``r·c`` (Zth changes by ~1e-12 Rth).

        >>> Cauer([1.0, 2.0, 3.0], [1.0, 0.0, 2.0]).with_capacitances()
        Cauer(r=(3.0, 3.0), c=(1.0, 2.0))
        """
        if all(self.c):
            return self
        r, c = list(self.r), list(self.c)
        for i in range(len(c) - 1, 0, -1):
            if c[i] == 0:
                r[i - 1] += r.pop(i)
                c.pop(i)
        if c[0] == 0:
            c[0] = 1e-12 * min(ri * ci for ri, ci in zip(r[1:], c[1:], strict=True)) / r[0]
        return Cauer(r, c)

    @classmethod
    def from_foster(cls, foster: Foster) -> Cauer:
        """Exact conversion of a Foster network."""
        return foster.to_cauer()

    def _foster(self) -> Foster:
        return _cached_foster(self)

    def to_foster(self) -> Foster:
        """Exact Cauer -> Foster conversion (bidiagonal SVD, high relative accuracy)."""
        return _cached_foster(self)

    def state_matrices(self) -> tuple[NDArray, NDArray]:
        """Capacitance vector C and conductance matrix G of ``C dθ/dt = -G θ + e0 P``."""
        n = self.order
        g = np.zeros((n, n))
        for i, r in enumerate(self.r):
            g[i, i] += 1 / r
            if i + 1 < n:
                g[i + 1, i + 1] += 1 / r
                g[i, i + 1] -= 1 / r
                g[i + 1, i] -= 1 / r
        return np.asarray(self.c), g


# --------------------------------------------------------------------------- conversions
def _poly_mul(a: list[Fraction], b: list[Fraction]) -> list[Fraction]:
    out = [Fraction(0)] * (len(a) + len(b) - 1)
    for i, x in enumerate(a):
        if x:
            for j, y in enumerate(b):
                out[i + j] += x * y
    return out


def _poly_add(a: list[Fraction], b: list[Fraction]) -> list[Fraction]:
    n = max(len(a), len(b))
    return [(a[i] if i < len(a) else 0) + (b[i] if i < len(b) else 0) for i in range(n)]


def _trim(a: list[Fraction]) -> list[Fraction]:
    while len(a) > 1 and a[-1] == 0:
        a = a[:-1]
    return a


def _foster_to_cauer(r: Sequence[float], tau: Sequence[float]) -> tuple[list[float], list[float]]:
    """Continued-fraction (Cauer I) expansion of Z(s) = Σ r/(1+sτ), exact in rationals.

    Polynomials are lists of coefficients, lowest power first. Z = N/D with deg D = n,
    deg N = n - 1. Then repeatedly: Y = D/N = s·C + Y', Z' = N/(D - sCN) = R + Z'', ...
    """
    rs = [Fraction(x) for x in r]
    ts = [Fraction(x) for x in tau]
    num: list[Fraction] = [Fraction(0)]
    den: list[Fraction] = [Fraction(1)]
    for ri, ti in zip(rs, ts, strict=True):  # N/D + r/(1+sτ) = (N(1+sτ) + rD) / (D(1+sτ))
        factor = [Fraction(1), ti]
        num = _poly_add(_poly_mul(num, factor), [ri * x for x in den])
        den = _poly_mul(den, factor)
    num, den = _trim(num), _trim(den)
    rr: list[float] = []
    cc: list[float] = []
    # admittance Y = den/num (deg den = deg num + 1)
    while True:
        c = den[-1] / num[-1]
        shifted = [Fraction(0)] + [c * x for x in num]  # s·C·N
        rem = _trim([a - b for a, b in zip(_poly_add(den, [0] * len(shifted)),
                                          _poly_add(shifted, [0] * len(den)), strict=True)])
        cc.append(float(c))
        # impedance Z' = num/rem, deg equal: R = leading ratio
        if len(rem) == 1 and rem[0] == 0:  # pragma: no cover - only for degenerate input
            raise DataFormatError("Foster network is degenerate (repeated time constants?)")
        rval = num[-1] / rem[-1]
        rest = _trim([a - rval * b for a, b in zip(num, rem, strict=True)])
        rr.append(float(rval))
        if len(rest) == 1 and rest[0] == 0:
            break
        den, num = rem, rest  # next admittance Y'' = rem/rest
    return rr, cc


def _lanczos_digits(foster: Foster) -> int:
    tau = np.asarray(foster.tau)
    span = max(1.0, math.log10(float(tau.max() / tau.min())))
    return int(60 + math.ceil(0.6 * foster.order * span))


def _cauer_impedance(cauer: Cauer, omega: NDArray) -> NDArray:
    """Input impedance of a Cauer ladder at ``omega`` (rad/s) by its continued fraction
    (forward evaluation, well conditioned in double precision)."""
    s = 1j * np.asarray(omega, dtype=float)
    z = np.full(s.shape, cauer.r[-1], dtype=complex)
    for i in range(cauer.order - 1, -1, -1):
        y = s * cauer.c[i] + 1.0 / z
        z = (cauer.r[i - 1] if i > 0 else 0.0) + 1.0 / y
    return z


def _lanczos_cauer(ladder: Foster, digits: int) -> Cauer:
    import mpmath

    with mpmath.workdps(digits):
        mpf = mpmath.mpf
        lam = [1 / mpf(t) for t in ladder.tau]
        w = [mpf(r) / mpf(t) for r, t in zip(ladder.r, ladder.tau, strict=True)]
        total = mpmath.fsum(w)
        q = [mpmath.sqrt(x / total) for x in w]
        n = len(lam)
        q_prev = [mpf(0)] * n
        beta = mpf(0)
        alphas, betas = [], []
        for k in range(n):
            v = [x * y for x, y in zip(lam, q, strict=True)]
            alpha = mpmath.fsum(x * y for x, y in zip(q, v, strict=True))
            alphas.append(alpha)
            if k == n - 1:
                break
            v = [vi - alpha * qi - beta * pi for vi, qi, pi in zip(v, q, q_prev, strict=True)]
            beta = mpmath.sqrt(mpmath.fsum(x * x for x in v))
            if beta == 0:  # pragma: no cover - only for repeated time constants
                raise DataFormatError("Foster network is degenerate (repeated time constants)")
            betas.append(beta)
            q_prev, q = q, [x / beta for x in v]
        rs, cs = [], [1 / total]
        g_prev = mpf(0)
        for i in range(n):
            g = alphas[i] * cs[i] - g_prev
            if g <= 0:
                raise ArithmeticError("precision lost")
            rs.append(1 / g)
            if i + 1 < n:
                cs.append(1 / (rs[i] ** 2 * betas[i] ** 2 * cs[i]))
            g_prev = g
        return Cauer([float(x) for x in rs], [float(x) for x in cs])


def _foster_to_cauer_lanczos(ladder: Foster) -> Cauer:
    digits = _lanczos_digits(ladder)
    omega = 1.0 / np.asarray(ladder.tau)
    want = (np.asarray(ladder.r) / (1 + 1j * omega[:, None] * np.asarray(ladder.tau))).sum(axis=1)
    for _ in range(4):  # check the input impedance at every pole; more digits if it is off
        try:
            cauer = _lanczos_cauer(ladder, digits)
        except (ArithmeticError, DataFormatError):
            digits *= 2
            continue
        if np.max(np.abs(_cauer_impedance(cauer, omega) / want - 1)) < 1e-9:
            return cauer
        digits *= 2
    raise DataFormatError(f"Foster -> Cauer at order {ladder.order}: no stable conversion "
                          f"(time constants too close?)")


def _cached_foster(cauer: Cauer) -> Foster:
    cached = cauer.__dict__.get("_foster_cache")
    if cached is None:
        full = cauer.with_capacitances()
        r, tau = (np.asarray(x, dtype=float) for x in _cauer_to_foster(full.r, full.c))
        keep = r > 0  # a mode the junction does not see (a nearly massless node) adds nothing
        cached = Foster.from_tau(r[keep], tau[keep])
        object.__setattr__(cauer, "_foster_cache", cached)
    return cached


def _cauer_to_foster(r: Sequence[float], c: Sequence[float]) -> tuple[NDArray, NDArray]:
    """Poles and residues of the Cauer input impedance.

    With ``C dθ/dt = -G θ + e0 P``, ``G = Aᵀ R⁻¹ A`` and ``B = R^-1/2 A C^-1/2 = U Σ Vᵀ``
    (upper bidiagonal: ``B_ii = 1/√(r_i c_i)``, ``B_i,i+1 = -1/√(r_i c_i+1)``),
    ``Z(s) = Σ v0k² / (C0 (s + σk²))``, so ``τk = 1/σk²`` and ``rk = v0k² τk / C0``.
    """
    rr, cc = np.asarray(r, dtype=float), np.asarray(c, dtype=float)
    sigma, v0 = singular_values(1 / np.sqrt(rr * cc), 1 / np.sqrt(rr[:-1] * cc[1:]))
    tau = 1 / sigma**2
    return v0**2 * tau / cc[0], tau


def _foster_to_cauer_bidiagonal(ladder: Foster) -> Cauer:
    """Cauer elements from the bidiagonal whose singular values are ``1/√τ`` and whose right
    vectors start with ``√(w_k / Σw)``, ``w_k = r_k/τ_k`` (inverse of :func:`_cauer_to_foster`)."""
    r, tau = np.asarray(ladder.r), np.asarray(ladder.tau)
    w = r / tau
    total = float(w.sum())
    d, e = bidiagonalize(1 / np.sqrt(tau), np.sqrt(w / total))
    rs, cs = np.empty(ladder.order), np.empty(ladder.order)
    cs[0] = 1 / total
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):  # Cauer() rejects
        for i in range(ladder.order):
            rs[i] = 1 / (d[i] ** 2 * cs[i])
            if i + 1 < ladder.order:
                cs[i + 1] = 1 / (rs[i] * e[i] ** 2)
    return Cauer(rs, cs)


def round_trip_error(foster: Foster, cauer: Cauer) -> float:
    """Largest relative difference in any R or τ between ``foster`` and ``cauer`` converted back.

    Parameters
    ----------
    foster : the original Foster ladder.
    cauer : its Cauer equivalent.

    Returns
    -------
    float : ``max |x' / x - 1|`` over all stage resistances and time constants.

    Examples
    --------
    >>> f = Foster.from_tau([1.0, 2.0], [1e-3, 1.0])
    >>> round_trip_error(f, f.to_cauer()) < 1e-12
    True
    """
    if cauer.order != foster.order:
        return math.inf
    back = cauer.to_foster()
    return float(max(np.max(np.abs(np.divide(back.r, foster.r) - 1)),
                     np.max(np.abs(np.divide(back.tau, foster.tau) - 1))))
