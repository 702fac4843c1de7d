"""The N-port ``.lib`` of an array model, and its check in ngspice against the model.

``.SUBCKT NAME TJ1 … TJN TREF``: one pin per cell (the heat goes in, the temperature is read),
then the reference. The model's network is written as it is — resistors and heat capacities to
node 0, the thermal ground — so the subcircuit is the fitted model itself, in every dialect
(plain R and C read the same in ngspice, PSPICE and LTspice; the header names the dialect).
:func:`check_array_lib` steps each cell in ngspice (under the dialect's compatibility mode)
and compares every pin with the model's exact response.

>>> from spicethermal.bench.array_devices import ArrayGeometry
>>> text = render_array_lib(ArrayGeometry(rows=1, cols=2).model(), name="PAIR")
>>> ".SUBCKT PAIR TJ1 TJ2 TREF" in text
True
"""

from __future__ import annotations

import os
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .. import __version__
from ..core.errors import DataFormatError
from ..engines.pwmsim import workers
from ..io.files import atomic_write_text
from .lib import DIALECTS, check_name, default_name
from .ngspice import sanitize_comment, simulator
from .templates import environment

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from ..array.model import ArrayModel

__all__ = ["check_array_lib", "export_array", "pins", "ramp_response", "render_array_lib",
           "step_bench"]

#: The reference pin of every array subcircuit.
REF_PIN = "TREF"


def pins(model: ArrayModel) -> list[str]:
    """The subcircuit's pins: ``TJ1`` ... ``TJN``, then ``TREF``.

    Parameters
    ----------
    model : ArrayModel
        The array.

    Returns
    -------
    list of str
    """
    return [f"TJ{k + 1}" for k in range(model.n_ports)] + [REF_PIN]


def _coupling(model: ArrayModel) -> str:
    dc = model.modes.dc()
    n = model.n_ports
    ratio = [dc[i, j] / dc[i, i] for i in range(n) for j in range(n) if i != j]
    return f"{100 * min(ratio):.3g} to {100 * max(ratio):.3g} %" if ratio else "none (one port)"


def _facts(model: ArrayModel) -> list[str]:
    fit = model.provenance.get("fit")
    lines = []
    if isinstance(fit, dict) and isinstance(fit.get("max_error"), int | float):
        lines.append(f"Fit: order {fit.get('order', '?')} (chain nodes per cell), worst element "
                     f"{100 * float(fit['max_error']):.3g} % of its Z_ii final value")
    span = fit.get("valid_t_s") if isinstance(fit, dict) else None
    if isinstance(span, list) and len(span) == 2:
        lines.append(f"Valid from {float(span[0]):.3g} s to {float(span[1]):.3g} s (the data's "
                     f"time range)")
    if model.provenance.get("device"):
        lines.append(f"device: {model.provenance['device']}")
    return [sanitize_comment(x) for x in lines]


def render_array_lib(model: ArrayModel, dialect: str = "ngspice", name: str | None = None,
                     filename: str = "array.lib") -> str:
    """The N-port subcircuit of ``model`` as text.

    Parameters
    ----------
    model : ArrayModel
        The array model.
    dialect : str
        ``ngspice``, ``pspice`` or ``ltspice``.
    name : str, optional
        Subcircuit name (default: the model's device, else the file's stem).
    filename : str
        File name quoted in the usage lines.

    Returns
    -------
    str
    """
    if dialect not in DIALECTS:
        raise DataFormatError(f"dialect {dialect!r}: expected one of {', '.join(DIALECTS)}")
    name = check_name(default_name(model, filename) if name is None else name)  # type: ignore[arg-type]
    pin = pins(model)
    n = model.n_ports
    spice_node = [pin[k] if k < n else f"N{k - n + 1}" for k in range(len(model.nodes))]

    def node(k: int) -> str:
        return REF_PIN if k < 0 else spice_node[k]

    ports = [{"pin": pin[k], "name": p.name,
              "place": None if p.x_mm is None else f"({p.x_mm:g}, {p.y_mm:g}) mm"}
             for k, p in enumerate(model.ports)]
    inner = [f"{spice_node[k]} = {model.nodes[k]}" for k in range(n, len(model.nodes))]
    taus = model.modes.tau
    ctx = {"name": name, "dialect": dialect, "version": __version__, "ports": ports,
           "pins": pin, "ref": REF_PIN, "reference": model.reference,
           "n_nodes": len(model.nodes), "coupling": _coupling(model),
           "taus": f"{taus.min():.4g} to {taus.max():.4g} ({taus.size} modes)",
           "facts": _facts(model), "inner": [sanitize_comment(x) for x in inner],
           "filename": sanitize_comment(filename, 80), "power_w": 0.1,
           "resistors": [{"a": node(a), "b": node(b), "value": r} for a, b, r in model.resistors],
           "capacitors": [{"a": node(a), "value": c} for a, c in model.capacitors]}
    return environment().get_template("lib/array.lib.j2").render(**ctx)


def export_array(model: ArrayModel, path: str | os.PathLike, dialect: str = "ngspice",
                 name: str | None = None) -> Path:
    """Write the N-port subcircuit atomically (see :func:`render_array_lib`).

    Parameters
    ----------
    model : ArrayModel
        The array model.
    path : str or os.PathLike
        The ``.lib`` file.
    dialect, name
        As for :func:`render_array_lib`.

    Returns
    -------
    Path
    """
    path = Path(path)
    return atomic_write_text(path, render_array_lib(model, dialect, name, path.name))


def step_bench(lib_path: str | os.PathLike, name: str, pin_names: list[str], heated: int,
               power_w: float, tstop_s: float, tmax_s: float, rise_s: float,
               reltol: float = 1e-5) -> str:
    """A deck that ramps ``power_w`` into pin ``heated`` over ``rise_s`` with the others off.

    Parameters
    ----------
    lib_path : str or os.PathLike
        The ``.lib`` to include.
    name : str
        Its subcircuit.
    pin_names : list of str
        Its pins (:func:`pins`).
    heated : int
        The heated port.
    power_w, tstop_s, tmax_s, rise_s : float
        Power, end of the transient, its largest step, the ramp's duration.
    reltol : float
        ngspice's relative tolerance.

    Returns
    -------
    str
    """
    return environment().get_template("bench/array_step.cir.j2").render(
        name=check_name(name), version=__version__, lib_path=str(lib_path), pins=pin_names,
        heated=pin_names[heated], power_w=power_w, tstop_s=tstop_s, tmax_s=tmax_s,
        rise_s=rise_s, reltol=reltol)


def ramp_response(model: ArrayModel, t_s: NDArray, rise_s: float) -> NDArray:
    """Exact Z(t) when the power ramps up linearly over ``rise_s`` (as the bench decks do),
    ``(len(t_s), N, N)``.

    Parameters
    ----------
    model : ArrayModel
        The array model.
    t_s : NDArray
        Times, s.
    rise_s : float
        Duration of the ramp, s.

    Returns
    -------
    NDArray
    """
    m = model.modes
    t = np.asarray(t_s, dtype=float)[:, None]
    lam = m.lam
    during = (t / lam + np.expm1(-lam * t) / lam ** 2) / rise_s
    late = 1 / lam - (np.exp(-lam * np.maximum(t - rise_s, 0)) - np.exp(-lam * t)) / (
        lam ** 2 * rise_s)
    f = np.where(t < rise_s, during, late)
    return np.einsum("ik,jk,tk->tij", m.w, m.w, f, optimize=True)


def check_array_lib(model: ArrayModel, dialect: str = "ngspice", *,
                    heated: list[int] | None = None, engine: str = "ngspice",
                    lib_text: str | None = None, name: str = "ARRAY_CHECK") -> dict:
    """Step each heated port in ngspice and compare every pin with the model.

    Parameters
    ----------
    model : ArrayModel
        The model the ``.lib`` was written from.
    dialect : str
        The ``.lib``'s dialect (ngspice runs it in that compatibility mode).
    heated : list of int, optional
        Ports to step, one deck each (default: every port).
    engine : str
        ``ngspice`` (``ngspice -b``, decks in parallel) or ``pyspice``.
    lib_text : str, optional
        The ``.lib`` to check (default: :func:`render_array_lib` of the model).
    name : str
        The subcircuit's name in ``lib_text``.

    Returns
    -------
    dict
        ``max_error`` (largest |ngspice − model| over every pin and time, fraction of the
        read pin's Z_ii final value), ``per_port`` (the same per heated port), ``t_s`` (the
        span compared), ``runs``.
    """
    heated = list(range(model.n_ports)) if heated is None else list(heated)
    taus = model.modes.tau
    tstop = 5 * float(taus.max())
    rise = 1e-3 * float(taus.min())
    text = lib_text if lib_text is not None else render_array_lib(model, dialect, name)
    backend = simulator(engine)
    dc = np.diag(model.modes.dc())
    pin = pins(model)
    with tempfile.TemporaryDirectory(prefix="spicethermal-array-") as tmp:
        lib = Path(tmp) / "array.lib"
        lib.write_text(text)
        decks = [step_bench(lib, name, pin, j, 1.0, tstop, tstop / 2000, rise) for j in heated]
        vectors = [f"V({p})" for p in pin[:-1]]
        with ThreadPoolExecutor(workers() if backend.name == "ngspice" else 1) as pool:
            waves = list(pool.map(lambda d: backend.run(d, vectors, dialect), decks))
    per_port = {}
    for j, wave in zip(heated, waves, strict=True):
        keep = wave.t_s >= 10 * rise
        exact = ramp_response(model, wave.t_s[keep], rise)[:, :, j]
        got = np.column_stack([wave[v][keep] for v in vectors])
        per_port[model.ports[j].name] = float(np.max(np.abs(got - exact) / dc[None, :]))
    return {"max_error": max(per_port.values()), "per_port": per_port,
            "t_s": [10 * rise, tstop], "runs": len(heated), "dialect": dialect,
            "engine": backend.name}
