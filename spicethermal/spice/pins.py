"""Names on an exported subcircuit's ``.SUBCKT`` line: the subcircuit's own and its pins.

A thermal subcircuit has a junction and a reference pin (and optionally the thermal ground of a
Cauer ladder); an electrothermal one (:mod:`spicethermal.spice.electrothermal`) has the diode's
anode and cathode in front of them. :class:`Pins` holds the names and their order, as
``export --pins`` spells them.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from ..core.errors import DataFormatError

if TYPE_CHECKING:  # pragma: no cover
    from ..model import ThermalModel

NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.\-]{0,63}")
PIN = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,31}")
#: Node names used inside the exported subcircuits: ladder nodes, the latent-heat helpers and
#: the electrothermal part's diode nodes (DJ the junction behind the series resistance, DT its
#: temperature in kelvin, DX the exponent, DI the current's value; DA spare).
INTERNAL = re.compile(r"(N|PCQ|PCS)[0-9]+|D[AJITX]", re.I)
RESERVED = {"end", "ends", "subckt", "control", "endc", "include", "lib", "param", "model",
            "tran", "ac", "dc", "op", "options", "option", "global", "func", "ic", "nodeset",
            "gnd", "0"}
ROLES = {"junction": "junction", "j": "junction", "case": "reference",
         "reference": "reference", "ref": "reference", "ambient": "ambient", "amb": "ambient",
         "anode": "anode", "a": "anode", "cathode": "cathode", "k": "cathode"}
THERMAL_ROLES = ("junction", "reference", "ambient")
ELECTRICAL_ROLES = ("anode", "cathode")


def check_name(name: str) -> str:
    """Validate a subcircuit name as vendors spell part numbers: a letter or digit, then up to
    63 letters, digits, ``_``, ``-`` or ``.``; not a SPICE keyword.

    >>> check_name("SPD22N08S2L-50"), check_name("2N7002")
    ('SPD22N08S2L-50', '2N7002')
    """
    if not isinstance(name, str) or not NAME.fullmatch(name) or name.lower() in RESERVED:
        raise DataFormatError(
            f"subcircuit name {name!r} is not allowed: use a letter or digit followed by up to "
            "63 letters, digits, '_', '-' or '.', not a SPICE keyword")
    return name


def default_name(model: ThermalModel, filename: str | os.PathLike = "") -> str:
    """A subcircuit name from the model's device (provenance ``device``) or the file's stem.

    Characters a name may not hold become ``_``; ``THERMAL_MODEL`` when nothing is left.

    >>> from spicethermal.core.ladder import Foster
    >>> from spicethermal.model import ThermalModel
    >>> default_name(ThermalModel(Foster.from_tau([1], [1]), provenance={"device": "my diode"}))
    'my_diode'
    >>> default_name(ThermalModel(Foster.from_tau([1], [1])), "out/IPB019N08N3.lib")
    'IPB019N08N3'
    """
    text = str(model.provenance.get("device") or Path(filename).stem or "")
    name = re.sub(r"[^A-Za-z0-9_.\-]+", "_", text).strip("_.-")[:64]
    try:
        return check_name(name)
    except DataFormatError:
        return "THERMAL_MODEL"


@dataclass(frozen=True)
class Pins:
    """Pin names of an exported subcircuit and their order on its ``.SUBCKT`` line.

    ``junction`` takes the heat (a current in), ``reference`` is the case or ambient the Zth
    was measured to, ``ambient`` (optional, Cauer only) the thermal ground the capacitors
    connect to instead of node 0. ``anode`` and ``cathode`` are the electrothermal part's
    electrical pins (:mod:`spicethermal.spice.electrothermal`), None on a thermal subcircuit.

    >>> Pins.parse("case=TC,junction=TJ").names
    ('TC', 'TJ')
    >>> Pins.parse("Tj,Tcase,Tamb").ambient
    'Tamb'
    >>> Pins.parse("TJ,TREF", electrical=True).names
    ('A', 'K', 'TJ', 'TREF')
    >>> Pins.parse("junction=Tj,anode=P,cathode=N,case=Tc", electrical=True).names
    ('Tj', 'P', 'N', 'Tc')
    """

    junction: str = "TJ"
    reference: str = "TREF"
    ambient: str | None = None
    order: tuple[str, ...] = ("junction", "reference")
    anode: str | None = None
    cathode: str | None = None

    @classmethod
    def parse(cls, text: str, electrical: bool = False) -> Pins:
        """``--pins`` text: comma-separated names in ``.SUBCKT`` order, or each as
        ``role=NAME``. Thermal roles: junction, case|reference, ambient (2 or 3 names, in that
        order when no role is given). With ``electrical`` (``export --electrothermal``) the
        roles anode and cathode come first (4 or 5 names: anode, cathode, junction,
        reference[, ambient]); given 2 or 3 names, the anode ``A`` and cathode ``K`` are put
        in front of them."""
        items = [x.strip() for x in str(text).split(",")]
        sizes = (2, 3, 4, 5) if electrical else (2, 3)
        positional = (*ELECTRICAL_ROLES, *THERMAL_ROLES) if electrical and len(items) > 3 \
            else THERMAL_ROLES
        if len(items) not in sizes or not all(items):
            what = ("2 to 5 comma-separated pin names (anode, cathode, junction, "
                    "reference[, ambient]), e.g. A,K,TJ,TCASE" if electrical else
                    "2 or 3 comma-separated pin names (junction, reference[, ambient]), "
                    "e.g. TJ,TCASE")
            raise DataFormatError(f"--pins {text!r}: give {what}")
        names: dict[str, str] = {}
        order = []
        for k, item in enumerate(items):
            role, _, name = item.rpartition("=")
            role = ROLES.get(role.strip().lower()) if role else positional[k]
            if role is None or role in names:
                raise DataFormatError(f"--pins {text!r}: item {item!r}: role must be junction, "
                                      "case, reference or ambient"
                                      + (", anode or cathode" if electrical else "")
                                      + ", each once")
            if role in ELECTRICAL_ROLES and not electrical:
                raise DataFormatError(f"--pins {text!r}: an {role} pin belongs to an "
                                      "electrothermal part (export --electrothermal)")
            names[role] = name.strip()
            order.append(role)
        if "junction" not in names or "reference" not in names:
            raise DataFormatError(f"--pins {text!r}: a junction and a reference pin are needed")
        if electrical:
            missing = [r for r in ELECTRICAL_ROLES if r not in names]
            if len(missing) == 1:
                raise DataFormatError(f"--pins {text!r}: name both the anode and the cathode, "
                                      f"or neither (then A and K)")
            if missing:
                names.update(anode="A", cathode="K")
                order = [*ELECTRICAL_ROLES, *order]
        try:
            return cls(names["junction"], names["reference"], names.get("ambient"),
                       tuple(order), names.get("anode"), names.get("cathode"))
        except DataFormatError as exc:
            raise DataFormatError(f"--pins {text!r}: {exc}") from None

    def __post_init__(self) -> None:
        seen = set()
        for name in self.names:
            if (not isinstance(name, str) or not PIN.fullmatch(name)
                    or name.lower() in RESERVED or INTERNAL.fullmatch(name)):
                raise DataFormatError(
                    f"pin name {name!r} is not allowed: use a letter followed by up to 31 "
                    "letters, digits or underscores, not a SPICE keyword, 0, GND or an inner "
                    "node name (N1, DJ, ...)")
            if name.lower() in seen:
                raise DataFormatError(f"pin name {name!r} appears twice")
            seen.add(name.lower())

    @property
    def names(self) -> tuple[str, ...]:
        """The pin names in ``.SUBCKT`` order."""
        return tuple(getattr(self, role) for role in self.order)

    @property
    def electrical(self) -> bool:
        """True when the pins include the anode and the cathode."""
        return self.anode is not None

    @property
    def ground(self) -> str:
        """Where a Cauer ladder's capacitors connect: the ambient pin, else node 0."""
        return self.ambient or "0"
