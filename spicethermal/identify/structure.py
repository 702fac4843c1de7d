"""Structure functions: the heat path as cumulative capacitance against cumulative resistance.

From a Foster ladder (fitted, or lumped from a time-constant spectrum,
:meth:`spicethermal.identify.spectrum.Spectrum.to_foster`) the exact Cauer equivalent gives the heat
path from the junction outwards: resistor ``r_k`` and capacitance ``c_k`` of each section.

* **Cumulative structure function** (Protonotarios–Wagner; JESD51-14): the points
  ``(ΣR_k, ΣC_k) = (Σ_{i≤k} r_i, Σ_{i≤k} c_i)``, ``k = 1..n``, from the junction outwards.
  Flat stretches (ΣC barely grows while ΣR does) are layers of small heat capacity and
  large resistance (die attach, thermal interface); steep rises are large masses (base
  plate, heat sink). The curve ends at ``ΣR = Rth``, where ΣC diverges (ambient).
* **Differential structure function** ``K = dΣC/dΣR``, here ``ΔΣC/ΔΣR`` between
  consecutive points, placed at the middle of the interval. For a uniform layer of
  conductivity λ, volumetric heat capacity cρ and cross-section A, ``K = λ cρ A²``: peaks
  mark where the heat spreads into a larger cross-section or a new material.

Two measurements of the same device mounted differently (dry, or with thermal paste) share
the structure function up to the interface and separate beyond it (JESD51-14 transient dual
interface method). :func:`separation` finds that point; see its docstring for the
definition.

The Cauer equivalent is exact at any order a structure function wants (50-150 stages, and up to
1000: :meth:`spicethermal.core.ladder.Foster.to_cauer`, rational continued fraction up to 12 stages,
bidiagonal inverse SVD checked by its round trip above).

>>> from spicethermal.core.ladder import Cauer
>>> sf = StructureFunction.from_ladder(Cauer([1.0, 2.0], [1e-3, 1.0]))
>>> sf.r_k_per_w.tolist(), sf.c_j_per_k.tolist()
([1.0, 3.0], [0.001, 1.001])
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..core.errors import DataFormatError
from ..core.ladder import Cauer, Foster
from .curves import ZthCurve
from .spectrum import Spectrum, time_constant_spectrum

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray


__all__ = ["SEPARATION_THRESHOLD", "Separation", "StructureFunction",
           "cauer_ladder", "separation", "structure_function"]

#: Default separation threshold: |Δ log10 ΣC| (0.05 decade = 12 % in ΣC).
SEPARATION_THRESHOLD = 0.05
#: Default stages per decade when a spectrum is lumped for a structure function.
STAGES_PER_DECADE = 10


# ------------------------------------------------------------------------ Foster -> Cauer
def cauer_ladder(ladder: Foster | Cauer) -> Cauer:
    """The exact Cauer equivalent of a ladder at any order (:meth:`Foster.to_cauer`).

    >>> cauer_ladder(Foster.from_tau([1.0], [2.0])).c
    (2.0,)
    """
    return ladder if isinstance(ladder, Cauer) else ladder.to_cauer()


# ------------------------------------------------------------------- structure functions
@dataclass(frozen=True, eq=False)
class StructureFunction:
    """Cumulative structure function of a heat path, from the junction outwards.

    Immutable. Build it with :meth:`from_ladder`, :meth:`from_spectrum` or
    :func:`structure_function`.

    Attributes
    ----------
    r_k_per_w : ΣR_k = Σ_{i≤k} r_i of the Cauer equivalent (K/W), increasing to Rth.
    c_j_per_k : ΣC_k = Σ_{i≤k} c_i (J/K), increasing.
    cauer : the Cauer ladder.
    t_resolved_s : time window the measurement resolves, if known.
    label : name of the source.
    """

    r_k_per_w: NDArray
    c_j_per_k: NDArray
    cauer: Cauer
    t_resolved_s: tuple[float, float] | None = None
    label: str = ""
    meta: dict[str, Any] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        for name in ("r_k_per_w", "c_j_per_k"):
            arr = np.array(getattr(self, name), dtype=float).ravel()
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        if self.r_k_per_w.size != self.c_j_per_k.size or self.r_k_per_w.size == 0:
            raise DataFormatError("StructureFunction: r_k_per_w and c_j_per_k need the same "
                                  "non-zero size")
        if self.t_resolved_s is not None:
            object.__setattr__(self, "t_resolved_s", (float(self.t_resolved_s[0]),
                                                      float(self.t_resolved_s[1])))
        object.__setattr__(self, "meta", dict(self.meta))

    # -- constructors --------------------------------------------------------------------
    @classmethod
    def from_ladder(cls, ladder: Foster | Cauer, *, t_resolved_s: tuple[float, float] | None
                    = None, label: str = "") -> StructureFunction:
        """From a Foster (converted exactly, :func:`cauer_ladder`) or Cauer ladder."""
        cauer = cauer_ladder(ladder)
        return cls(np.cumsum(cauer.r), np.cumsum(cauer.c), cauer, t_resolved_s, label)

    @classmethod
    def from_spectrum(cls, spectrum: Spectrum, n_per_decade: float = STAGES_PER_DECADE
                      ) -> StructureFunction:
        """From a time-constant spectrum lumped to ``n_per_decade`` Foster stages per decade."""
        cauer = cauer_ladder(spectrum.to_foster(n_per_decade))
        return cls(np.cumsum(cauer.r), np.cumsum(cauer.c), cauer, spectrum.t_resolved_s,
                   spectrum.label, {"method": spectrum.method, "n_per_decade": n_per_decade,
                                    "resolution_decades": spectrum.resolution_decades})

    # -- views -----------------------------------------------------------------------------
    @property
    def rth_k_per_w(self) -> float:
        """Total resistance, the end of the curve (K/W)."""
        return float(self.r_k_per_w[-1])

    @property
    def order(self) -> int:
        """Number of Cauer sections."""
        return int(self.r_k_per_w.size)

    def time_constants_s(self) -> NDArray:
        """A local time scale of each point, ``ΣR_k · ΣC_k`` (s): roughly when the heat front
        reaches it; used to tell which part of the curve the measurement resolves."""
        return self.r_k_per_w * self.c_j_per_k

    def resolved(self) -> NDArray:
        """Mask of the points whose local time scale lies inside :attr:`t_resolved_s`
        (all points when the window is unknown)."""
        if self.t_resolved_s is None:
            return np.ones(self.order, dtype=bool)
        tk = self.time_constants_s()
        return (tk >= self.t_resolved_s[0]) & (tk <= self.t_resolved_s[1])

    def resolved_c_range(self) -> tuple[float, float]:
        """ΣC range (J/K) of the resolved points."""
        c = self.c_j_per_k[self.resolved()]
        if c.size == 0:
            raise DataFormatError(f"{self.label or 'structure function'}: no point lies in the "
                                  f"resolved time window")
        return float(c[0]), float(c[-1])

    def resolved_r_range(self) -> tuple[float, float]:
        """ΣR range (K/W) of the resolved points."""
        r = self.r_k_per_w[self.resolved()]
        if r.size == 0:
            raise DataFormatError(f"{self.label or 'structure function'}: no point lies in the "
                                  f"resolved time window")
        return float(r[0]), float(r[-1])

    def c_at(self, r_k_per_w: ArrayLike) -> NDArray:
        """ΣC (J/K) at ΣR, linear in (ΣR, ln ΣC) between the points (clipped to the ends)."""
        return np.exp(np.interp(np.asarray(r_k_per_w, dtype=float), self.r_k_per_w,
                                np.log(self.c_j_per_k)))

    def r_at(self, c_j_per_k: ArrayLike) -> NDArray:
        """ΣR (K/W) at ΣC, the inverse of :meth:`c_at` (clipped to the ends)."""
        return np.interp(np.log(np.asarray(c_j_per_k, dtype=float)), np.log(self.c_j_per_k),
                         self.r_k_per_w)

    def differential(self) -> tuple[NDArray, NDArray]:
        """Differential structure function: (ΣR at interval middles (K/W), K = ΔΣC/ΔΣR
        (J/K²·W))."""
        r, c = self.r_k_per_w, self.c_j_per_k
        return 0.5 * (r[1:] + r[:-1]), np.diff(c) / np.diff(r)

    def to_dict(self) -> dict[str, Any]:
        """The JSON form printed by ``spicethermal structure --json``."""
        return {"cumulative": {"r_k_per_w": self.r_k_per_w.tolist(),
                               "c_j_per_k": self.c_j_per_k.tolist()}}

    def __str__(self) -> str:
        """One line: sections, Rth, and ΣC where the measurement resolves it.

        The last ΣC is not the device's: the curve ends at ``ΣR = Rth``, where the heat reaches
        the ambient (an infinite capacity) and the spectrum's time constants run past the
        record, so ΣC diverges there (10⁴-10⁶ J/K for a device of a fraction of a J/K). The
        figure that means something is ΣC at the end of the resolved range.

        >>> from spicethermal.core.ladder import Cauer
        >>> sf = StructureFunction.from_ladder(Cauer([1.0, 2.0, 0.01], [1e-3, 0.1, 1e4]),
        ...                                    t_resolved_s=(1e-4, 1.0))
        >>> text = str(sf)
        >>> "resolved ΣR 1..3 K/W, where ΣC = 0.101 J/K" in text, "diverges to 1e+04 J/K" in text
        (True, True)
        """
        text = (f"{self.label or 'structure function'}: {self.order} Cauer sections, "
                f"Rth = {self.rth_k_per_w:.4g} K/W")
        last = f"{self.c_j_per_k[-1]:.3g} J/K"
        if self.t_resolved_s is not None and self.resolved().any():
            lo, hi = self.resolved_r_range()
            c_hi = self.resolved_c_range()[1]
            text += f"; resolved ΣR {lo:.3g}..{hi:.3g} K/W, where ΣC = {c_hi:.3g} J/K"
            if self.c_j_per_k[-1] > 1.5 * c_hi:
                text += (f" (beyond, ΣC diverges to {last} toward the ambient, an infinite heat "
                         f"sink)")
            return text
        return text + f", ΣC = {last} at ΣR = Rth (where it diverges toward the ambient)"


def structure_function(source: ZthCurve | Spectrum | Foster | Cauer, *,
                       n_per_decade: float = STAGES_PER_DECADE, **spectrum_options: Any
                       ) -> StructureFunction:
    """Structure function of a Zth curve (through its time-constant spectrum), a spectrum or
    a ladder.

    Parameters
    ----------
    source : ZthCurve, Spectrum, Foster or Cauer
        What to analyse; a curve goes through
        :func:`~spicethermal.identify.spectrum.time_constant_spectrum`.
    n_per_decade : float
        Foster stages per decade of τ when a spectrum is lumped.
    **spectrum_options
        Passed to the spectrum of a curve.

    Returns
    -------
    StructureFunction
        Cumulative ΣR, ΣC from the junction outwards and the differential function.

    >>> from spicethermal.core.ladder import Foster
    >>> sf = structure_function(Foster.from_tau([1.0, 2.0], [1e-3, 1e-1]))
    >>> round(sf.rth_k_per_w, 12), sf.order
    (3.0, 2)
    """
    if isinstance(source, Foster | Cauer):
        return StructureFunction.from_ladder(source)
    if isinstance(source, ZthCurve):
        source = time_constant_spectrum(source, **spectrum_options)
    if isinstance(source, Spectrum):
        return StructureFunction.from_spectrum(source, n_per_decade)
    raise DataFormatError(f"structure_function: cannot use a {type(source).__name__}")


# -------------------------------------------------------------------------- separation
@dataclass(frozen=True)
class Separation:
    """Where two cumulative structure functions part (see :func:`separation`).

    ``r_k_per_w`` is ``None`` when they do not part within the compared range.
    ``first_exceeds_r_k_per_w`` is the first ΣR at which the difference exceeds the threshold
    at all (even if the curves come together again after it).
    """

    r_k_per_w: float | None
    c_j_per_k: float | None
    threshold_decades: float
    r_range_k_per_w: tuple[float, float]
    max_difference_decades: float
    labels: tuple[str, str] = ("", "")
    first_exceeds_r_k_per_w: float | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {"r_k_per_w": self.r_k_per_w, "c_j_per_k": self.c_j_per_k,
                "first_exceeds_r_k_per_w": self.first_exceeds_r_k_per_w,
                "threshold_decades": self.threshold_decades,
                "r_range_k_per_w": list(self.r_range_k_per_w),
                "max_difference_decades": self.max_difference_decades,
                "labels": list(self.labels)}

    def __str__(self) -> str:
        a, b = (x or "?" for x in self.labels)
        lo, hi = self.r_range_k_per_w
        if self.r_k_per_w is None:
            return (f"{a} and {b} do not separate over ΣR {lo:.3g}..{hi:.3g} K/W "
                    f"(|Δlog10 ΣC| ≤ {self.max_difference_decades:.3f} < "
                    f"{self.threshold_decades})")
        text = (f"{a} and {b} separate at ΣR = {self.r_k_per_w:.4g} K/W "
                f"(ΣC = {self.c_j_per_k:.4g} J/K; |Δlog10 ΣC| > {self.threshold_decades} "
                f"from there to the end of ΣR {lo:.3g}..{hi:.3g} K/W")
        first = self.first_exceeds_r_k_per_w
        if first is not None and first < self.r_k_per_w:
            text += f"; first exceeded, transiently, at {first:.3g} K/W"
        return text + ")"


def separation(a: StructureFunction, b: StructureFunction, *,
               threshold_decades: float = SEPARATION_THRESHOLD, points: int = 2000
               ) -> Separation:
    """Where two cumulative structure functions part for good.

    Definition: the curves are compared on a uniform grid of ``points`` ΣR values over the
    range where **both** are resolved (:meth:`StructureFunction.resolved_r_range`; this drops
    the start built from times before the first trusted sample — the √t extension of the
    masked electrical transient — and the end built from times beyond the record, where ΣC
    diverges towards the ambient), through :meth:`StructureFunction.c_at`. With
    ``Δ(ΣR) = |log10 ΣC_a − log10 ΣC_b|``, the separation point is the first ΣR from which
    ``Δ > threshold_decades`` holds up to the end of the compared range (default
    :data:`SEPARATION_THRESHOLD` = 0.05 decade, a 12 % difference in ΣC). "For good"
    matters on real data: near the junction two measurements of one device wiggle apart and
    together again by a few hundredths of a decade (a 1-3 % difference of the early Zth, from
    noise and the power setting), while beyond the interface they only diverge.
    ``c_j_per_k`` is the geometric mean ΣC of the two there.

    >>> from spicethermal.core.ladder import Cauer
    >>> common = ([0.2, 0.3], [0.01, 0.05])
    >>> dry = StructureFunction.from_ladder(Cauer(common[0] + [1.0, 2.0], common[1] + [0.1, 20]))
    >>> wet = StructureFunction.from_ladder(Cauer(common[0] + [0.3, 2.0], common[1] + [0.1, 20]))
    >>> round(separation(dry, wet).r_k_per_w, 2)   # just after the shared 0.2 + 0.3 K/W
    0.55
    """
    if not (math.isfinite(threshold_decades) and threshold_decades > 0):
        raise DataFormatError(f"threshold_decades = {threshold_decades!r}: must be > 0")
    lo_a, hi_a = a.resolved_r_range()
    lo_b, hi_b = b.resolved_r_range()
    lo, hi = max(lo_a, lo_b), min(hi_a, hi_b)
    labels = (a.label, b.label)
    if not hi > lo:
        raise DataFormatError(f"{a.label or 'a'} and {b.label or 'b'}: the resolved ΣR ranges "
                              f"({lo_a:.3g}..{hi_a:.3g} and {lo_b:.3g}..{hi_b:.3g} K/W) do not "
                              f"overlap")
    r = np.linspace(lo, hi, int(points))
    ca, cb = a.c_at(r), b.c_at(r)
    diff = np.abs(np.log10(ca) - np.log10(cb))
    over = np.flatnonzero(diff > threshold_decades)
    first = float(r[over[0]]) if over.size else None
    below = np.flatnonzero(diff <= threshold_decades)
    if below.size and below[-1] == r.size - 1:
        return Separation(None, None, float(threshold_decades), (lo, hi), float(diff.max()),
                          labels, first)
    i = int(below[-1]) + 1 if below.size else 0
    return Separation(float(r[i]), float(math.sqrt(ca[i] * cb[i])), float(threshold_decades),
                      (lo, hi), float(diff.max()), labels, first)
