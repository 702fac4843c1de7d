"""The HTML report of the main job: sections built from the results, one jinja2 template.

The page (``index.html``) sits beside its PNG figures and ``.lib`` files and reads offline.
Numbers are formatted here; the template only lays them out (autoescaped HTML).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import __version__
from ..io.files import atomic_write_text
from ..spice.templates import environment

SECTION_IDS = ("calibration", "fit", "impedance", "table1", "table2", "electrothermal",
               "diagnosis", "netlists",
               "limits")


@dataclass
class Section:
    id: str
    title: str
    paragraphs: list[str] = field(default_factory=list)
    tables: list[dict] = field(default_factory=list)
    figures: list[dict] = field(default_factory=list)
    code: list[dict] = field(default_factory=list)
    verdict: str = ""

    def figure(self, path: Path | None, out: Path, caption: str) -> None:
        if path is not None and Path(path).exists():
            self.figures.append({"src": os.path.relpath(path, out), "caption": caption})

    def table(self, header: Sequence[str], rows: Sequence[Sequence[Any]],
              caption: str = "") -> None:
        self.tables.append({"header": list(header), "rows": [list(r) for r in rows],
                            "caption": caption})


def render(title: str, subtitle: str, summary: Sequence[str], sections: Sequence[Section],
           elapsed_s: float) -> str:
    """The report page as HTML text."""
    return environment().get_template("report/index.html.j2").render(
        title=title, subtitle=subtitle, summary=list(summary), sections=list(sections),
        elapsed_s=elapsed_s, version=__version__)


def _g(x: float, digits: int = 4) -> str:
    return f"{x:.{digits}g}"


def _signed(x: float) -> str:
    return f"{x:+.2f}"


def usage_snippet(lib: Path, name: str, power_w: float) -> str:
    """A copy-paste SPICE deck that uses an exported subcircuit under 1 kHz, 50 % PWM."""
    return (f".include {lib.name}\n"
            f"X1 TJ TAMB {name}\n"
            f"Vamb TAMB 0 DC 25                 ; ambient 25 degC: V(TJ) is Tj in degC\n"
            f"Ipd 0 TJ PULSE(0 {power_w:g} 0 1u 1u 0.5m 1m)  ; {power_w * 1e3:g} mW, 1 kHz, 50 %\n"
            f".tran 10u 60 0 1m\n"
            f".end")


def write_demo_report(out: Path, *, bundle, calibration, curves, model, fit, libs, table2,
                      diagnosis, better, before, after, diagnosis_figures, table1, summary,
                      elapsed_s: float, law_fit=None, circuit=None) -> Path:
    """Write ``out/index.html`` for the demo run and return its path (``law_fit`` and
    ``circuit``: the heater's diode law and Table 2 through the bench circuit, when the bundle
    has forward points)."""
    figs = out / "figures"
    secs: list[Section] = []

    s = Section("calibration", "1. TSP calibration (paper Fig. 2)")
    s.paragraphs.append(
        f"The heater diode's forward voltage against temperature (as the bench records it, "
        f"relative to its value at the ambient), fitted "
        f"{'linearly' if calibration.degree == 1 else 'with a quadratic'}: "
        f"K-factor {calibration.k_factor_mv_per_k:.3f} mV/K"
        f"{' at mid-range' if calibration.degree == 2 else ''}, residual RMS "
        f"{calibration.rms_mv:.3f} mV ({calibration.rms_k:.3f} K) over "
        f"{calibration.points} points. Linearity test: {calibration.linearity}.")
    s.figure(figs / "fig2_calibration.png", out, "Fig. 2 — TSP voltage (mV) against the "
             "hot-plate temperature with the law used; its bow, the points' and the law's "
             "departure from a straight line in K; the law's residuals in K")
    secs.append(s)

    s = Section("fit", "2. Thermal impedance and the fitted ladder (paper Fig. 7)")
    c0 = curves[0]
    s.paragraphs.append(
        f"Cooling curve {c0.label} at {c0.power_w:g} W gives Rth = {c0.rth_k_per_w:.2f} K/W "
        f"(eq. 1). {_early_text(c0)} The ladder order was chosen automatically "
        f"({fit.criterion}; orders tried: "
        + ", ".join(f"{k}: {v:.1f}" for k, v in sorted(fit.criterion_values.items()))
        + f"), with ΣR = Rth held; residual RMS {fit.rms_k_per_w * 1e3:.2f} mK/W.")
    s.table(["stage", "R (K/W)", "u(R) (K/W)", "τ (s)", "u(τ) (s)", "C (J/K)"],
            [[i + 1, _g(st["r_k_per_w"]), _g(st["u_r_k_per_w"], 2), _g(st["tau_s"]),
              _g(st["u_tau_s"], 2), _g(st["c_j_per_k"])] for i, st in enumerate(fit.stages)],
            "Foster ladder (fit)")
    s.table(["node", "R towards TREF (K/W)", "C to node 0 (J/K)"], cauer_rows(model),
            "Equivalent Cauer ladder (exact conversion), nodes as the .lib files name them: "
            "TJ the junction, N1 … inward layers, each capacity to node 0, the thermal ground")
    if len(curves) > 1:
        s.paragraphs.append("All cooling curves: " + "; ".join(
            f"{c.label} at {c.power_w:g} W: Rth = {c.rth_k_per_w:.2f} K/W" for c in curves)
            + ". Rth that changes with power is the sign of a temperature-dependent device.")
    s.figure(figs / "fig7_fit.png", out, "Fig. 7 — (a) Zth(t) in K/W: the fitted ladder over "
             "the measured curve, (b) data − fit, (c) the Foster and Cauer ladders")
    secs.append(s)

    s = Section("impedance", "3. Duty-cycle impedance curves (paper Fig. 8)")
    s.paragraphs.append(
        "Zth,D(t) = Rth · r_D(t) in K/W for D = 0 … 0.9: the paper's eq. 3, "
        "r_D = D + (1 − D)·r(t) (dashed), against the exact peak of a periodic pulse train "
        "(solid). Eq. 3 is conservative: it overstates the peak for pulses shorter than the "
        "middle time constants.")
    s.figure(figs / "fig8_impedance.png", out, "Fig. 8 — peak thermal impedance (K/W) of a "
             "periodic pulse train against the pulse width, one curve per duty cycle")
    secs.append(s)

    s = Section("table1", "4. Bench validation on the MUR880E (paper Table 1)")
    s.paragraphs.append(
        f"The simulated bench measured the MUR880E junction-to-case cooling curve; r(t) "
        f"against the datasheet curve (Rth_jc = {table1.rth_datasheet_k_per_w:g} K/W). "
        f"Measured Rth = {table1.rth_measured_k_per_w:.3f} K/W. {table1.early}")
    rows = []
    for i, t in enumerate(table1.t_s):
        row = [f"{t * 1e3:.2f}", f"{table1.measured_r[i]:.4f}" + (
            "*" if table1.extrapolated[i] else ""), f"{table1.datasheet_r[i]:.3f}",
            f"{table1.error_percent[i]:+.1f}"]
        if table1.reference_r is not None:
            row += [f"{table1.reference_r[i]:.3f}", f"{table1.reference_error_percent[i]:+.1f}"]
        rows.append(row)
    head = ["time (ms)", "measured r(t) (1)", "datasheet r(t) (1)", "error (%)"]
    if table1.reference_r is not None:
        head += ["paper's measured r(t) (1)", "paper's error (%)"]
    s.table(head, rows, "Table 1 — * extrapolated by the √t law")
    s.figure(figs / "table1_mur880e.png", out, "MUR880E normalised impedance r(t) = Zth/Rth: "
             "measured against the datasheet curve, and the error in %")
    secs.append(s)

    s = Section("table2", "5. PWM: measured vs model in ngspice (paper Table 2)")
    pwm = [p for p in table2.points if p.dataset == "pwm"]
    window = pwm[0].info.get("window_s", 0.0) if pwm else 0.0
    s.paragraphs.append(
        f"Each point is the bench reading (junction temperature at the end of a "
        f"{window * 1e6:.0f} µs power-off sample window, periodic steady state) against the "
        f"exported ladder simulated in ngspice from its periodic steady state. RMS "
        f"{table2.rms_k:.2f} K, worst {table2.max_abs_k:.2f} K.")
    duties = sorted({p.at["duty"] for p in pwm})
    freqs = sorted({p.at["freq_hz"] for p in pwm})
    by = {(p.at["freq_hz"], p.at["duty"]): p for p in pwm}
    rows = []
    for f in freqs:
        row: list[Any] = [f"{f / 1e3:g}"]
        for d in duties:
            p = by.get((f, d))
            row += ([f"{p.measured_c:.2f}", f"{p.model_c:.2f}", _signed(p.residual_k)]
                    if p else ["", "", ""])
        rows.append(row)
    head = ["f (kHz)"] + [h for d in duties
                          for h in (f"T_exp at D = {d:.0%} (°C)", "T_mod (°C)", "Δ (K)")]
    s.table(head, rows, "Table 2 — Δ = measured − model")
    s.figure(figs / "table2_delta.png", out, "PWM readings minus the ngspice model, "
             "Δ = T_exp − T_mod in K, by frequency and duty cycle (bars and heat map)")
    secs.append(s)
    if law_fit is not None and circuit is not None:
        secs.append(electrothermal_section(out, law_fit, circuit, table2, libs))

    s = Section("diagnosis", "6. Diagnosis: what the linear ladder misses")
    doc = diagnosis.to_dict()
    s.verdict = (f"Verdict: {doc['verdict']['class']}"
                 + (f" — {', '.join(doc['verdict']['effects'])}" if doc["verdict"]["effects"]
                    else "") + f": {doc['verdict']['reason']}")
    s.table(["where", "at", "residual (K)"],
            [[w["dataset"], _at(w["at"]), _signed(w["residual_k"])]
             for w in doc["baseline"]["worst"]],
            f"Worst misfits of the baseline, the linear {doc['baseline']['order']}-stage ladder "
            f"fitted to every data set (RMS {doc['baseline']['rms_k']:.3g} K)")
    s.table(["candidate effect", "form", "fitted parameters", "ΔBIC (1)", "RMS (K)",
             "improvement", "evidence"],
            [[c["effect"] + ("" if c["catalogued"] else " (not in the catalogue)"), c["form"],
              ", ".join(f"{k} = {_g(v, 3)}" for k, v in c["params"].items()),
              f"{c['delta_bic']:+.1f}", f"{c['rms_k']:.3g}", f"{c['improvement']:.3g}×",
              c["evidence"]]
             for c in doc["candidates"]], "Candidates, best first")
    if better is not None:
        s.paragraphs.append(
            f"With {', '.join(diagnosis.effects)} added (fitted parameters in the candidates "
            f"table below), the RMS "
            f"error over every data set falls from {before.rms_k:.3g} K to {after.rms_k:.3g} K "
            f"({before.rms_k / max(after.rms_k, 1e-12):.3g}× lower; RMS staircase: "
            f"{diagnosis.staircase()}); worst from {before.max_abs_k:.3g} K to "
            f"{after.max_abs_k:.3g} K.")
        s.table(["data set", "RMS before (K)", "RMS after (K)"],
                [[name, f"{cb.rms_k:.3g}", f"{after.by_dataset()[name].rms_k:.3g}"]
                 for name, cb in before.by_dataset().items()])
    for path in diagnosis_figures or ():
        s.figure(path, out, diagnosis_caption(path))
    secs.append(s)

    s = Section("netlists", "7. Exported SPICE models")
    s.paragraphs.append(
        f"{len(libs)} files, each holding .SUBCKT NAME TJ TREF: heat flow in W is a current "
        f"into TJ; temperatures are absolute, V(TJ) in °C with TREF driven at the ambient in "
        f"°C (the temperature rise in K is V(TJ) − V(TREF)). The electrothermal parts hold "
        f".SUBCKT NAME A K TJ TREF: the diode between A and K heats TJ itself (section 5b). "
        f"The header of each file carries Rth, the time constants and the provenance.")
    s.table(["file", "dialect", "topology", "size"],
            [[os.path.relpath(p, out), *_dialect_topology(p), f"{p.stat().st_size} B"]
             for p in libs])
    s.code.append({"caption": "Copy-paste usage (ngspice, 1 kHz 50 % PWM at the bench power)",
                   "text": usage_snippet(libs[0], "ACTUATOR",
                                         bundle.pwm.power_w if bundle.pwm else 0.1)})
    s.code.append({"caption": f"{os.path.relpath(libs[1], out)}",
                   "text": Path(libs[1]).read_text()})
    secs.append(s)

    s = Section("limits", "8. Model limits")
    s.paragraphs += [
        "The Foster network reproduces Zth(t) exactly, but its inner nodes are not physical "
        "temperatures: do not connect to them and do not chain Foster models. Use the Cauer "
        "files when coupling the device to another thermal network (heat sink, board).",
        "The ladder is linear and holds near the temperatures it was measured at; the "
        "diagnosis above says which effect to add when it does not. Device effects use "
        "absolute temperatures: drive TREF with the ambient temperature in °C.",
        "Below the first valid sample (about 100 µs after the electrical transient) Zth is "
        "extrapolated: PWM predictions above ~10 kHz lean on that extrapolation."]
    secs.append(s)

    html = render("spicethermal — thermal model of the thermopneumatic actuator",
                  f"Simulated bench run of {bundle.device or 'the actuator'}; "
                  "the paper's procedure end to end.", summary, secs, elapsed_s)
    return atomic_write_text(out / "index.html", html)


def electrothermal_section(out: Path, law_fit, circuit: dict, table2, libs) -> Section:
    """The report's section on the heater as an electrothermal part: the diode law fitted to
    the forward points, Table 2 from the bench circuit (Fig. 3) beside the thermal-only deck,
    and a run of the circuit (Vf, I, Tj)."""
    figs = out / "figures"
    law, u = law_fit.law, law_fit.u
    s = Section("electrothermal", "5b. The heater as an electrothermal part: Vf(I, T) and "
                                  "Table 2 through the bench circuit")
    s.paragraphs.append(
        f"The bench read the heater's forward voltage at {law_fit.residual_v.size} points "
        "(a few currents, each in the middle of a short pulse, at every calibration "
        "temperature, and under the sense current); SPICE's diode law was fitted to them and to "
        "the TSP calibration, each point at its junction temperature (the pulse's and the "
        "sense current's heating from the thermal model). The exported part "
        ".SUBCKT NAME A K TJ TREF carries it: its current follows Vf(I, T(TJ)), its I·V heats "
        "the ladder, TJ is a pin.")
    s.table(["diode law parameter", "value", "1σ uncertainty"],
            [["N (ideality)", f"{law.n:.4f}", f"{u['n']:.2g}"],
             ["IS at 25 °C", f"{law.is_a:.4g} A", f"{100 * u['is_a'] / law.is_a:.2g} %"],
             ["RS", f"{law.rs_ohm:.4g} Ω", f"{u['rs_ohm']:.2g} Ω"],
             ["XTI", f"{law.xti:.3g}", f"{u['xti']:.2g}"],
             ["EG", f"{law.eg_ev:.4f} eV", f"{u['eg_ev']:.2g} eV"]]
            + [[f"residual, {k} points", f"{1e3 * v:.3g} mV",
                f"{law_fit.rms_k[k]:.2g} K"] for k, v in law_fit.rms_v.items()],
            "The fitted law Vf(I, T) = N·Vt·ln(I/Is(T) + 1) + RS·I")
    s.figure(figs / "diode_law.png", out, "The heater's forward voltage (V) against the "
             "current (A) at each calibration temperature: the bench's points, the fitted "
             "law, and the residuals in mV")
    pwm = [p for p in table2.points if p.dataset == "pwm"]
    rows = []
    for p in sorted(pwm, key=lambda p: (p.at["duty"], p.at["freq_hz"])):
        c = circuit["readings_c"][(p.at["freq_hz"], p.at["duty"])]
        rows.append([f"{p.at['freq_hz'] / 1e3:g}", f"{100 * p.at['duty']:g}",
                     f"{p.measured_c:.2f}", f"{p.model_c:.3f}", f"{c:.3f}",
                     f"{c - p.model_c:+.3f}"])
    worst = max(abs(float(r[-1])) for r in rows)
    s.paragraphs.append(
        "Table 2 again, now from the paper's measurement circuit (Fig. 3) in ngspice: the "
        "PIC's PWM switching the heating current that the power loop sets, the sense current, "
        f"the TSP read at the end of the {circuit['window_s'] * 1e6:.0f} µs sample window "
        "through the calibration, as the bench reads it. It agrees with the thermal-only "
        f"deck within {worst:.3f} K.")
    s.table(["f (kHz)", "D (%)", "T_exp (°C)", "thermal-only deck (°C)",
             "bench circuit (°C)", "circuit − thermal (K)"], rows,
            "Table 2 — the readings from the circuit deck beside the thermal-only deck")
    run = circuit["run"]
    s.figure(figs / "circuit_pwm.png", out,
             f"The bench circuit at {run.state.freq_hz / 1e3:g} kHz, "
             f"{100 * run.state.duty:g} % duty: forward voltage (V), current (mA) and junction "
             "temperature (°C) over three periods and the sample window")
    heater = [p for p in libs if "electrothermal" in Path(p).name]
    if heater:
        s.code.append({"caption": f"{os.path.relpath(heater[0], out)}",
                       "text": Path(heater[0]).read_text()})
    return s


#: What each figure of :func:`spicethermal.viz.plots.diagnosis_figures` shows, by file stem.
DIAGNOSIS_CAPTIONS = {
    "diagnosis_steps": "RMS error over every data set (K) after each effect the diagnosis "
                       "added: the staircase",
    "diagnosis_before_after": "Residuals, measured − model in K, of every data set the effects "
                              "change: the linear ladder (left), the model with the effects "
                              "found (right)",
    "diagnosis_step": "Residuals, measured − model in K, before and after the effect added "
                      "in step {k}",
    "diagnosis_candidates": "RMS error (K) of the linear ladder and of each candidate effect "
                            "fitted to the bundle, the verdict highlighted",
    "diagnosis_table2": "Table 2 residuals Δ(f, D) in K with the explanations the diagnosis "
                        "tried",
}


def diagnosis_caption(path: str | os.PathLike) -> str:
    """The caption of a diagnosis figure: what it shows (:data:`DIAGNOSIS_CAPTIONS`).

    Parameters
    ----------
    path : str or os.PathLike
        A file written by :func:`spicethermal.viz.plots.diagnosis_figures`.

    Returns
    -------
    str
        The caption; a file the table does not know is named as a figure of the diagnosis.

    Examples
    --------
    >>> diagnosis_caption("figures/diagnosis_step_2.png")
    'Residuals, measured − model in K, before and after the effect added in step 2'
    """
    stem = Path(path).stem
    head, _, k = stem.rpartition("_")
    if k.isdigit() and head in DIAGNOSIS_CAPTIONS:
        return DIAGNOSIS_CAPTIONS[head].format(k=k)
    return DIAGNOSIS_CAPTIONS.get(stem, f"Diagnosis figure: {stem.replace('_', ' ')}")


def cauer_rows(model) -> list[list[str]]:
    """The exact Cauer ladder of ``model`` as the ``.lib`` files lay it out: node (``TJ``,
    ``N1``, ...), its resistor towards TREF (K/W) and its capacity to node 0 (J/K).

    >>> from spicethermal.core.ladder import Cauer
    >>> from spicethermal.model import ThermalModel
    >>> cauer_rows(ThermalModel(Cauer([1.0, 2.0], [1e-3, 0.5])))
    [['TJ', '1', '0.001'], ['N1', '2', '0.5']]
    """
    cauer = model.ladder.to_cauer() if model.ladder.topology != "cauer" else model.ladder
    return [["TJ" if i == 0 else f"N{i}", _g(r), _g(c)]
            for i, (r, c) in enumerate(zip(cauer.r, cauer.c, strict=True))]


def _early_text(curve) -> str:
    early = getattr(curve, "early", None)
    if early is None or not getattr(early, "detected", False):
        return ""
    return (f"The electrical transient masked the first {early.masked_s[1] * 1e6:.0f} µs "
            f"({early.masked_points} points), extrapolated back by the √t law.")


def _at(at) -> str:
    if "freq_hz" in at:
        return f"{at['freq_hz'] / 1e3:g} kHz, D = {at['duty']:.0%}"
    if "t_s" in at:
        return f"t = {at['t_s']:.3g} s"
    return ", ".join(f"{k} = {_g(v, 3)}" for k, v in at.items())


def _dialect_topology(path: Path) -> list[str]:
    parts = Path(path).stem.split("_")
    return [parts[-2], parts[-1]]


def figure_is_nontrivial(path: str | os.PathLike) -> bool:
    """A PNG that exists, decodes, and is not a blank canvas."""
    from matplotlib.image import imread

    img = imread(str(path))
    return img.ndim == 3 and min(img.shape[:2]) >= 100 and float(np.std(img[..., :3])) > 0.02
