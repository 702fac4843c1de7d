"""The main job, end to end on the simulated bench (what ``spicethermal demo`` runs).

It orchestrates every room (bench, identify, fit, spice, analysis, viz, report) and is none of
them: it sits at the top of the package, and nothing imports it but the ``demo`` command.

bench run of the actuator → bundle → Zth → automatic fit → the heater's diode law Vf(I, T) →
``.lib`` files (ngspice, PSPICE, LTspice × Foster, Cauer, and the electrothermal part) → the
paper's Table 2 through ngspice, from the thermal-only deck and from the bench circuit around the
electrothermal part → diagnosis → the effect added → error before/after; and the MUR880E
validation (Table 1). Everything lands in one directory with an HTML report (``index.html``)
that reads offline.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from .analysis.compare import compare
from .analysis.diagnose import diagnose
from .bench.session import run_bench
from .core.errors import SpiceThermalError
from .core.progress import enabled
from .engines.circuit import CircuitPwm
from .fit.diode import fit_electrical
from .fit.ladder import fit_model
from .identify.curves import ZthCurve
from .identify.datasheet import table1
from .identify.readings import calibration_fit
from .io.bundle import Bundle
from .io.datasheet import mur880e
from .io.files import write_json
from .report import html as report
from .spice.electrothermal import export_electrothermal
from .spice.lib import DIALECTS, TOPOLOGIES, export
from .viz import plots

#: The simulated devices. The actuator bench has the real bench's artefacts (electrical
#: transient after the cut, 100 µs sample window, a slightly nonlinear TSP) and the device hides
#: a temperature coefficient (the paper saw Rth fall as power and temperature rise) for the
#: diagnosis to find.
ACTUATOR_URL = ("sim://actuator?seed={seed}&effects=electrical-transient,sample-window,"
                "tsp-nonlinearity,temperature-coefficient")
MUR880E_URL = "sim://mur880e?seed={seed}"
SUBCKT = {"actuator": "ACTUATOR", "mur880e": "MUR880E"}
#: The ``.lib`` files' temperature convention: absolute, the command line's default (node
#: voltages in °C, TREF driven with the ambient), as the report's copy-paste deck uses them.
TEMPERATURE = "absolute"


@dataclass
class Steps:
    """Numbered progress lines on stderr: ``[3/9] fitting the ladder ... 0.21 s``.

    Shown like every progress display (:func:`spicethermal.core.progress.enabled`): not with
    ``quiet`` and not when stderr is not a terminal; the timings are kept either way.

    >>> steps = Steps(total=1, quiet=True)
    >>> steps.run("adding", lambda: 1 + 1), list(steps.timings)
    (2, ['adding'])
    """

    total: int
    quiet: bool = False
    done: int = 0
    timings: dict[str, float] = field(default_factory=dict)

    def run(self, title: str, work: Callable[[], Any]) -> Any:
        shown = enabled(self.quiet)
        self.done += 1
        if shown:
            print(f"[{self.done}/{self.total}] {title} ...", end="", file=sys.stderr, flush=True)
        t0 = time.perf_counter()
        try:
            result = work()
        except BaseException:
            if shown:
                print(" failed", file=sys.stderr, flush=True)
            raise
        dt = time.perf_counter() - t0
        self.timings[title] = dt
        if shown:
            print(f" {dt:.2f} s", file=sys.stderr, flush=True)
        return result


@dataclass(frozen=True)
class DemoResult:
    """Where everything went, and the five-line summary.

    Attributes
    ----------
    out : Path
        The output directory.
    report : Path
        The HTML report (``out/index.html``).
    libs : tuple of Path
        Every ``.lib`` file written.
    summary : tuple of str
        The five lines ``spicethermal demo`` prints.
    timings : dict of str to float
        Seconds per step, by the step's title.
    """

    out: Path
    report: Path
    libs: tuple[Path, ...]
    summary: tuple[str, ...]
    timings: dict[str, float]


def run_demo(out: str | Path = "out/demo", seed: int = 1, quiet: bool = False) -> DemoResult:
    """Run the whole job on the simulated bench and write the report into ``out``.

    Parameters
    ----------
    out : path-like
        The output directory (created).
    seed : int
        The simulated bench's seed.
    quiet : bool
        No progress lines on stderr.

    Returns
    -------
    DemoResult
        The report, the ``.lib`` files and a summary.

    Examples
    --------
    >>> result = run_demo("out/demo", seed=1, quiet=True)  # doctest: +SKIP
    >>> result.report.name  # doctest: +SKIP
    'index.html'
    """
    out = Path(out)
    figs = out / "figures"
    figs.mkdir(parents=True, exist_ok=True)
    steps = Steps(total=12, quiet=quiet)
    t_start = time.perf_counter()

    # 1. the bench ------------------------------------------------------------------------
    act_dir = steps.run("simulated bench: actuator (calibration, Rth, 2 cooling curves, PWM grid)",
                        lambda: run_bench(ACTUATOR_URL.format(seed=seed), out / "actuator",
                                          progress=not quiet))
    bundle = Bundle.read(act_dir)

    # 2. calibration and Zth --------------------------------------------------------------
    def calibrate_and_extract():
        cal = calibration_fit(bundle)
        curves = ZthCurve.from_bundle(bundle)
        plots.fig_calibration(cal, figs / "fig2_calibration.png")
        return cal, curves

    cal, curves = steps.run("TSP calibration and Zth(t) from the cooling curves",
                            calibrate_and_extract)

    # 3. fit --------------------------------------------------------------------------------
    def fit():
        model, result = fit_model(curves[0], provenance={"device": bundle.device,
                                                         "bundle": str(act_dir)})
        model.save(out / "actuator_model.json")
        plots.fig7(result, figs / "fig7_fit.png", title=curves[0].label)
        return model, result

    model, fit_result = steps.run("automatic ladder fit (order and values)", fit)

    # 3b. the heater's diode law ------------------------------------------------------------
    def electrical():
        law_fit = fit_electrical(bundle, model)
        if law_fit is None:
            return model, None
        plots.fig_diode_fit(law_fit, bundle.forward, figs / "diode_law.png")
        with_law = replace(model, electrical=law_fit.law)
        with_law.save(out / "actuator_model.json")
        return with_law, law_fit

    model, law_fit = steps.run("the heater's diode law Vf(I, T) from the forward points",
                               electrical)

    # 4. export ------------------------------------------------------------------------------
    def export_all():
        paths = []
        for dialect in DIALECTS:
            for topology in TOPOLOGIES:
                paths.append(export(model, out / "lib" / f"actuator_{dialect}_{topology}.lib",
                                    dialect, topology, SUBCKT["actuator"],
                                    temperature=TEMPERATURE))
        if model.electrical is not None:  # the heater as an electrothermal part
            paths += [export_electrothermal(
                model, out / "lib" / f"actuator_heater_{dialect}_electrothermal.lib", dialect,
                "cauer", SUBCKT["actuator"] + "_HEATER", temperature=TEMPERATURE)
                for dialect in DIALECTS]
        return tuple(paths)

    libs = steps.run("export .lib: ngspice, PSPICE, LTspice × Foster, Cauer, electrothermal",
                     export_all)

    # 5. Table 2 through ngspice ------------------------------------------------------------
    def table2():
        cmp = compare(model, bundle, engine="ngspice", datasets=["pwm"])
        plots.fig_table2(cmp, figs / "table2_delta.png")
        plots.fig8(model.ladder, figs / "fig8_impedance.png")
        return cmp

    table2_cmp = steps.run("the paper's Table 2: 18 PWM points in ngspice", table2)

    # 5b. Table 2 through the bench circuit (Fig. 3) around the electrothermal part ----------
    def table2_circuit():
        pwm = bundle.pwm
        if model.electrical is None or pwm is None:
            return None
        ambient = bundle.ambient_c if bundle.ambient_c is not None else 25.0
        sim = CircuitPwm(model, tref_c=ambient)
        states = sim.grid(pwm.powers_w, pwm.freq_hz, pwm.duty, pwm.sample_window_s)
        run = sim.run(float(pwm.powers_w[0]), 1e3, 0.5, pwm.sample_window_s)
        plots.fig_circuit(run, figs / "circuit_pwm.png")
        tref = pwm.tref_c if pwm.tref_c is not None else [ambient] * len(states)
        # the reading as each row's temperature, as the thermal-only deck's column gives it
        readings = {(s.freq_hz, s.duty): float(t) + s.reading_k
                    for s, t in zip(states, tref, strict=True)}
        return {"readings_c": readings, "run": run, "window_s": pwm.sample_window_s}

    circuit = steps.run("Table 2 through the bench circuit around the electrothermal heater",
                        table2_circuit)

    # 6. diagnosis ---------------------------------------------------------------------------
    # the same default path as `spicethermal diagnose BUNDLE`: one baseline, one set of numbers
    diag = steps.run("diagnosis: which physical effect is missing", lambda: diagnose(bundle))

    # 7. add the effect ----------------------------------------------------------------------
    def improve():
        before, after = diag.baseline, diag.final
        effect = diag.verdict_effect
        if effect is None:
            return None, before, before, ()
        better = diag.model()
        better.save(out / f"actuator_model_{effect}.json")
        paths = tuple(export(better, out / "lib" / f"actuator_{effect}_{dialect}_cauer.lib",
                             dialect, "cauer", SUBCKT["actuator"] + "_TC",
                             temperature=TEMPERATURE) for dialect in DIALECTS)
        return better, before, after, paths

    better, before, after, effect_libs = steps.run("add the effect and compare again", improve)
    libs = (*libs, *effect_libs)  # every .lib written, counted and listed once
    diag_figs = steps.run("diagnosis figures",
                          lambda: plots.diagnosis_figures(diag, figs))

    # 8. MUR880E validation -------------------------------------------------------------------
    def validate():
        d = run_bench(MUR880E_URL.format(seed=seed), out / "mur880e",
                      actions=("calibrate", "rth", "cooling"), progress=not quiet)
        t1 = table1(Bundle.read(d), mur880e())
        plots.fig_table1(t1, figs / "table1_mur880e.png")
        return t1

    t1 = steps.run("MUR880E bench validation against the datasheet (Table 1)", validate)

    # 9. report -------------------------------------------------------------------------------
    elapsed = time.perf_counter() - t_start
    summary = (
        f"actuator: Rth = {model.rth:.1f} K/W, {fit_result.order}-stage ladder "
        f"(time constants {min(model.ladder.time_constants()):.2g} s to "
        f"{max(model.ladder.time_constants()):.2g} s), chosen by {fit_result.criterion}",
        f"Table 2 in ngspice: RMS {table2_cmp.rms_k:.2f} K, worst {table2_cmp.max_abs_k:.2f} K "
        f"over {len(table2_cmp.points)} PWM points" + _circuit_summary(law_fit, circuit,
                                                                     table2_cmp),
        f"diagnosis: {diag.verdict_effect or 'no catalogued effect'} — {diag.verdict.reason}",
        (f"with {', '.join(diag.effects)}: RMS {before.rms_k:.3g} K -> {after.rms_k:.3g} K "
         f"({before.rms_k / max(after.rms_k, 1e-12):.3g}x lower)") if better is not None else
        f"model RMS over all data sets {before.rms_k:.2f} K (nothing to add)",
        f"MUR880E vs datasheet r(t): worst error {max(abs(t1.error_percent)):.1f} % "
        f"(the paper's bench: 13.3 %); {len(libs)} .lib files in {out / 'lib'}",
    )
    page = steps.run("HTML report", lambda: report.write_demo_report(
        out, bundle=bundle, calibration=cal, curves=curves, model=model, fit=fit_result,
        libs=libs, table2=table2_cmp, diagnosis=diag, better=better, before=before, after=after,
        diagnosis_figures=diag_figs, table1=t1, summary=summary, elapsed_s=elapsed,
        law_fit=law_fit, circuit=circuit))
    write_json(out / "summary.json", {"summary": summary, "timings_s": steps.timings})
    return DemoResult(out, page, tuple(libs), summary, steps.timings)


def _circuit_summary(law_fit, circuit, table2_cmp) -> str:
    """The summary's words on the electrothermal part: its law and Table 2 from the circuit."""
    if law_fit is None or circuit is None:
        return ""
    diff = [circuit["readings_c"][(p.at["freq_hz"], p.at["duty"])] - p.model_c
            for p in table2_cmp.points if p.dataset == "pwm"]
    law = law_fit.law
    return (f"; through the bench circuit around the electrothermal heater (diode law N = "
            f"{law.n:.3f}, RS = {law.rs_ohm:.3g} ohm) within "
            f"{max(abs(d) for d in diff):.3f} K of the thermal-only deck")


__all__ = ["DemoResult", "SpiceThermalError", "run_demo"]
