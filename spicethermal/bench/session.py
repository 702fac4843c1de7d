"""Bench sessions: a measurement plan run on the bench and added to a bundle, losing nothing.

A session holds the bundle's lock (:func:`spicethermal.io.files.locked`) from start to end, so a
second writer stops with a one-line error (or waits, ``wait=True``). Raw bytes go to
``BUNDLE/raw/<session>/`` inside the live bundle, appended and fsynced before they are
processed (:class:`~spicethermal.bench.link.RawLog`); a new bundle starts empty on disk
for that. The data sets measured are *added*: a rerun gets a new file name (``cooling_3.csv``,
``calibration_2.csv``); a single section's previous entry (calibration, pwm, the Rth summary)
moves to the manifest's ``superseded`` list and its file stays; only ``replace=[NAME]`` puts
new data in the place of a listed file. The bundle is then replaced in one atomic step
(:meth:`spicethermal.io.bundle.Bundle.write`). Killed at any moment, the bundle holds every data
set it held before plus the raw log of the session.

The measurement plan (powers, settling times, the PWM grid) comes from
:data:`~spicethermal.bench.plan.PLANS`, chosen by the board name the device reports; every value
can be overridden. How new data sets join the old ones is :mod:`spicethermal.bench.merge`.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import sys
import time
from collections.abc import Sequence
from dataclasses import asdict, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import DataFormatError, InstrumentError, SpiceThermalError
from ..identify.readings import converter
from ..io.bundle import MANIFEST, Bundle, CalibrationTable, CoolingTable, ForwardTable, PwmTable
from ..io.files import clean_leftovers, locked
from . import protocol as p
from .client import ACTIONS, ARRAY_ACTIONS, FORWARD_PROTOCOL, BenchClient, Run
from .coupling import measure_coupling
from .merge import SECTIONS, add_datasets
from .plan import PLANS, Plan

if TYPE_CHECKING:  # pragma: no cover
    from ..identify.calibration import Converter


# --------------------------------------------------------------------------- conversion
class TspConversion:
    """Junction temperature from the TSP, through the calibration.

    The TSP is the heater diode's forward voltage minus the reference diode's (which sits on
    the board, at the room ambient that the auxiliary thermocouple reads outside calibration).
    The calibration recorded ``g(T) = Vf(T) − Vf(T_cal,ref)``; so a reading ``v`` at reference
    temperature ``T_rd`` gives ``g(Tj) = v + g(T_rd)``.
    """

    def __init__(self, calibration: Converter) -> None:
        self.cal = calibration

    def tj_c(self, v_tsp_v: np.ndarray, t_ref_diode_c: float) -> np.ndarray:
        g_ref = float(self.cal.voltage(t_ref_diode_c))
        return self.cal.temperature(np.asarray(v_tsp_v, dtype=float) + g_ref, margin_k=40.0)


def _mean(samples: Sequence[p.Sample], attr: str) -> float:
    if not samples:
        raise InstrumentError(f"no samples to average for {attr}")
    return float(np.mean([getattr(s, attr) for s in samples]))


# --------------------------------------------------------------------------- whole runs
class Session:
    """One bench run adding data sets to the bundle ``out_dir`` (see the module's text)."""

    def __init__(self, url: str, out_dir: Path, plan: Plan | None, overrides: dict,
                 progress: bool, replace_names: Sequence[str] = (), wait: bool = False) -> None:
        self.url = url
        self.out_dir = Path(out_dir)
        self.plan_given = plan
        self.overrides = overrides
        self.progress_on = progress
        self.replace_names = tuple(replace_names)
        self.wait = wait

    def _raw_dir(self, action: str) -> Path:
        stamp = time.strftime("%Y%m%dT%H%M%S")
        raw = self.out_dir / "raw"
        run_dir, k = raw / f"{stamp}-{action}", 1
        while run_dir.exists():
            k += 1
            run_dir = raw / f"{stamp}-{action}-{k}"
        return run_dir

    def _adopt_old_raw_logs(self) -> None:
        """Move raw logs that spicethermal 0.1 left in ``BUNDLE.raw/`` (a run killed while
        its logs were moved out) back into the bundle's ``raw/``."""
        old = self.out_dir.parent / f"{self.out_dir.name}.raw"
        if not old.is_dir() or old.is_symlink() or not self.out_dir.is_dir():
            return
        (self.out_dir / "raw").mkdir(exist_ok=True)
        for entry in sorted(old.iterdir()):
            target = self.out_dir / "raw" / entry.name
            if not target.exists():
                os.rename(entry, target)
        with contextlib.suppress(OSError):
            old.rmdir()

    def _check_replace(self, previous: Bundle, actions: Sequence[str]) -> None:
        measured = {SECTIONS[a] for a in actions if a in SECTIONS}
        if "calibrate" in actions:
            measured.add("forward")
        kinds = {t.file: s for s, ts in (("calibration", [previous.calibration]),
                                         ("cooling", previous.cooling), ("pwm", [previous.pwm]),
                                         ("forward", [previous.forward]))
                 for t in ts if t is not None}
        for name in self.replace_names:
            if name not in kinds:
                raise DataFormatError(f"--replace {name}: not a data file of {self.out_dir} "
                                      f"(listed: {', '.join(sorted(kinds)) or 'none'})")
            if kinds[name] not in measured:
                raise DataFormatError(f"--replace {name}: this run measures no "
                                      f"{kinds[name]} data set")

    def run(self, actions: Sequence[str]) -> Path:
        for a in actions:
            if a not in ACTIONS + ARRAY_ACTIONS:
                raise DataFormatError(f"bench: unknown action {a!r}; expected "
                                      f"{', '.join(ACTIONS + ARRAY_ACTIONS)}")
        out = self.out_dir
        with locked(out, wait=self.wait):
            clean_leftovers(out)
            created = not out.exists() or not any(out.iterdir())
            if (out / MANIFEST).exists():
                previous = Bundle.read(out)
            elif not created:
                raise DataFormatError(f"{out}: exists and is not a bundle; not writing into it")
            else:
                previous = Bundle()
            self._adopt_old_raw_logs()
            self._check_replace(previous, actions)
            if previous.calibration is None and "calibrate" not in actions:
                needs = [a for a in actions if a in ("cooling", "pwm", "coupling")]
                if needs:  # said now, not after the measurement
                    raise DataFormatError(f"bench {needs[0]}: needs a calibration (run 'bench "
                                          f"calibrate' into the same bundle first, or 'bench "
                                          f"run')")
            if created:  # the raw log needs a home that is a valid bundle at every instant
                previous.write(out)
            raw_dir = self._raw_dir("-".join(actions) if len(actions) < 4 else "run")
            try:
                with BenchClient(self.url, raw_dir, progress=self.progress_on) as bench:
                    plan = self.plan_given or PLANS.get(bench.info.name, Plan())
                    if self.overrides:
                        plan = replace(plan, **self.overrides)
                    bench.check_limits([plan.settle_s, plan.calibration_settle_s,
                                        plan.pwm_settle_s], plan.cooling_t_last_s)
                    try:
                        new = self._measure(bench, plan, actions, previous)
                    finally:
                        bench.progress.close()
                        if sys.exc_info()[0] is not None:
                            try:
                                bench.abort()  # heater off
                            except Exception:
                                pass
            except SpiceThermalError as exc:
                raw = raw_dir / "raw_frames.bin"
                if raw.exists() and raw.stat().st_size:
                    raise type(exc)(f"{exc} (raw data of this session kept in {raw_dir})"
                                    ) from None
                shutil.rmtree(raw_dir, ignore_errors=True)
                if created:
                    shutil.rmtree(out, ignore_errors=True)
                elif raw_dir.parent.is_dir() and not any(raw_dir.parent.iterdir()):
                    raw_dir.parent.rmdir()
                raise
            session = f"raw/{raw_dir.name}/"
            for key in ("calibration", "pwm", "forward"):
                if new.get(key) is not None:
                    new[key] = replace(new[key], extra={**new[key].extra, "raw": session})
            new["cooling"] = [replace(c, extra={**c.extra, "raw": session})
                              for c in new.get("cooling", [])]
            if new.get("coupling") is not None:
                new["coupling"] = replace(new["coupling"],
                                          extra={**new["coupling"].extra, "raw": session})
            taken = set(os.listdir(out))
            bundle = add_datasets(new["base"], new, taken, self.replace_names)
            bundle = bundle.with_(extra={**bundle.extra,
                                         "bench": self._bench_info(bench, plan, session)})
            bundle.write(out)
        return out

    def _bench_info(self, bench: BenchClient, plan: Plan, raw: str) -> dict:
        return {"port": self.url, "board": bench.info.name, "firmware": bench.info.firmware,
                "protocol": bench.info.proto, "raw": raw,
                "link": bench.link.stats.report(), "plan": asdict(plan)}

    # -- measuring -------------------------------------------------------------------------
    def _measure(self, bench: BenchClient, plan: Plan, actions: Sequence[str],
                 previous: Bundle) -> dict:
        """The new data sets by section (see :func:`add_datasets`), and under ``base`` the
        previous bundle with this run's device, reference and ambient."""
        base = previous.with_(device=previous.device or plan.description,
                              reference=plan.reference)
        new: dict = {}
        steps = {"calibrate": (plan.calibration_settle_s + plan.forward_settle_s)
                 * len(plan.calibration_c),
                 "rth": plan.settle_s,
                 "cooling": (plan.settle_s + plan.cooling_t_last_s) * len(plan.cooling_powers_w),
                 "pwm": plan.pwm_settle_s * len(plan.pwm_freqs_hz) * len(plan.pwm_duties),
                 "coupling": (plan.settle_s + plan.cooling_t_last_s) * bench.info.ports}
        prog = bench.progress
        prog.total = sum(steps[a] for a in actions)
        prog.show("connected")
        state = {"base": 0.0}

        def status(m: p.Status) -> None:
            prog.show(extra=min(m.elapsed_ms / 1e3, state["base"]))

        bench.on_status = status
        ambient: list[float] = []

        def step(label: str, budget: float) -> None:
            state["base"] = budget
            prog.show(label)

        calibration = previous.calibration
        if "calibrate" in actions:
            calibration, forward = self._calibrate(bench, plan, step)
            new["calibration"] = calibration
            if forward is not None:
                new["forward"] = forward
        conv = None
        if calibration is not None:
            conv = TspConversion(converter(calibration, "auto"))
        if "rth" in actions:
            step(f"rth at {plan.rth_power_w:g} W", plan.settle_s)
            run = bench.rth(plan.rth_power_w, plan.settle_s, plan.window_s, plan.n_readings)
            prog.advance(plan.settle_s)
            new["rth"] = self._rth_summary(run, conv, plan, bench)
            ambient += [s.taux_c for s in run.samples]
        if "cooling" in actions:
            tables = []
            for k, power in enumerate(plan.cooling_powers_w, start=1):
                step(f"cooling curve {k} at {power:g} W", plan.settle_s + plan.cooling_t_last_s)
                run = bench.cooling(power, plan.settle_s, plan.window_s, plan.n_readings,
                                    plan.cooling_t_first_s, plan.cooling_t_last_s,
                                    plan.per_decade)
                prog.advance(plan.settle_s + plan.cooling_t_last_s)
                tables.append(self._cooling_table(run, conv, plan, k))
                ambient += [s.taux_c for s in run.samples]
            new["cooling"] = tables
        if "pwm" in actions:
            new["pwm"] = self._pwm(bench, plan, conv, step, ambient)
        if "coupling" in actions:
            new["coupling"] = measure_coupling(bench, plan, conv, step)
        if ambient:
            base = base.with_(ambient_c=round(float(np.mean(ambient)), 4))
        new["base"] = base
        return new

    def _calibrate(self, bench: BenchClient, plan: Plan, step
                   ) -> tuple[CalibrationTable, ForwardTable | None]:
        """The TSP calibration and, where the plan and the firmware have it, the forward
        voltage at each calibration temperature: the sense current's (the calibration's own
        readings of the heater's voltage) and one point per pulsed current."""
        temps, volts, rows = [], [], []
        forward = bool(plan.forward_currents_a)
        if forward and bench.info.proto < FORWARD_PROTOCOL:
            forward = False
            print(f"bench: firmware {bench.info.firmware} (protocol {bench.info.proto}) has no "
                  "forward-voltage procedure: no forward section (export --electrothermal needs "
                  "it; update the firmware to 1.2)", file=sys.stderr)
        i_sense = bench.info.i_sense_ua / 1e6
        for t_set in plan.calibration_c:
            step(f"calibration at {t_set:g} degC", plan.calibration_settle_s)
            run = bench.calibrate(t_set, plan.calibration_settle_s, plan.calibration_n,
                                  plan.calibration_interval_s)
            bench.progress.advance(plan.calibration_settle_s)
            cal = run.of_kind(p.KIND_CAL)
            temps.append(round(_mean(cal, "taux_c"), 4))
            volts.append(round(_mean(cal, "v_tsp_v"), 8))
            if not forward:
                continue
            if i_sense > 0:
                rows.append((temps[-1], i_sense, round(_mean(cal, "v_d_uv") / 1e6, 7), 0.0))
            step(f"forward voltage at {t_set:g} degC", plan.forward_settle_s)
            fwd = bench.forward(t_set, plan.forward_settle_s, plan.forward_pulse_s,
                                plan.forward_n, plan.forward_interval_s,
                                plan.forward_currents_a).of_kind(p.KIND_FORWARD)
            bench.progress.advance(plan.forward_settle_s)
            for k in range(len(plan.forward_currents_a)):
                group = fwd[k * plan.forward_n:(k + 1) * plan.forward_n]
                rows.append((temps[-1], round(_mean(group, "i_ua") / 1e6, 8),
                             round(_mean(group, "v_d_uv") / 1e6, 7), group[0].t_s))
        table = CalibrationTable(temp_c=temps, v_tsp_v=volts, file="calibration.csv")
        if not rows:
            return table, None
        arr = np.array(rows)
        return table, ForwardTable(arr[:, 0], arr[:, 1], arr[:, 2], arr[:, 3],
                                   sense_current_a=i_sense if i_sense > 0 else None,
                                   file="forward.csv")

    @staticmethod
    def _window_s(bench: BenchClient, plan: Plan) -> float:
        return 0.0 if bench.info.caps & p.CAP_IDEAL_HOLD else plan.window_s

    def _rth_summary(self, run: Run, conv: TspConversion | None, plan: Plan,
                     bench: BenchClient) -> dict:
        steady, power = run.of_kind(p.KIND_STEADY), run.of_kind(p.KIND_POWER)
        p_w = _mean(power, "power_w")
        tref = _mean(steady, "tamb_c")
        out = {"power_w": round(p_w, 7), "tref_c": round(tref, 4),
               "sample_window_s": self._window_s(bench, plan), "readings": len(steady),
               "v_tsp_v": round(_mean(steady, "v_tsp_v"), 8)}
        if conv is not None:
            tj = float(np.mean(conv.tj_c([s.v_tsp_v for s in steady], _mean(run.samples,
                                                                           "taux_c"))))
            out["tj_c"] = round(tj, 4)
            out["rth_k_per_w"] = round((tj - tref) / p_w, 5)
        return out

    def _cooling_table(self, run: Run, conv: TspConversion | None, plan: Plan, k: int):
        steady, power = run.of_kind(p.KIND_STEADY), run.of_kind(p.KIND_POWER)
        curve = run.of_kind(p.KIND_CURVE)
        if not curve:
            raise InstrumentError(f"{bench_name(run)}: the cooling curve holds no samples")
        t_s = np.array([s.t_s for s in curve])
        v = np.array([s.v_tsp_v for s in curve])
        tref = np.array([s.tamb_c for s in curve])
        extra = {"window_s": plan.window_s, "v_tsp_window_v": round(_mean(steady, "v_tsp_v"), 8)}
        kw: dict = {}
        if conv is not None:
            t_rd = _mean(run.samples, "taux_c")
            kw["tj_c"] = np.round(conv.tj_c(v, t_rd), 5)
            extra["tj_window_c"] = round(float(np.mean(conv.tj_c(
                [s.v_tsp_v for s in steady], t_rd))), 5)
        else:
            kw["v_tsp_v"] = v
        return CoolingTable(t_s=t_s, power_w=round(_mean(power, "power_w"), 7),
                            tref_c=np.round(tref, 4),
                            tref_steady_c=round(_mean(steady, "tamb_c"), 4),
                            file=f"cooling_{k}.csv", extra=extra, **kw)

    def _pwm(self, bench: BenchClient, plan: Plan, conv: TspConversion, step,
             ambient: list[float]):
        rows = []
        for duty in plan.pwm_duties:
            for freq in plan.pwm_freqs_hz:
                step(f"pwm {freq / 1e3:g} kHz, duty {duty:g}", plan.pwm_settle_s)
                run = bench.pwm(plan.pwm_power_w, freq, duty, plan.pwm_settle_s, plan.window_s,
                                plan.pwm_n, plan.pwm_interval_s)
                bench.progress.advance(plan.pwm_settle_s)
                steady, power = run.of_kind(p.KIND_STEADY), run.of_kind(p.KIND_POWER)
                t_rd = _mean(run.samples, "taux_c")
                ambient += [s.taux_c for s in run.samples]
                tj = float(np.mean(conv.tj_c([s.v_tsp_v for s in steady], t_rd)))
                rows.append((freq, duty, round(tj, 4), round(_mean(steady, "tamb_c"), 4),
                             round(_mean(power, "power_w"), 7)))
        arr = np.array(rows)
        return PwmTable(freq_hz=arr[:, 0], duty=arr[:, 1], tj_c=arr[:, 2], tref_c=arr[:, 3],
                        row_power_w=arr[:, 4], power_w=plan.pwm_power_w,
                        sample_window_s=self._window_s(bench, plan), file="pwm.csv")


def bench_name(run: Run) -> str:
    return p.PROC_NAMES.get(run.proc, "bench")


def run_bench(url: str, out_dir: str | os.PathLike, *, progress: bool = False,
              actions: Sequence[str] = ACTIONS, plan: Plan | None = None,
              replace_names: Sequence[str] = (), wait: bool = False, **overrides) -> Path:
    """Run the bench at ``url`` and write (or update) the bundle ``out_dir``.

    Parameters
    ----------
    url : any pyserial URL; ``sim://actuator`` or ``sim://mur880e`` (with options, see
        :mod:`.protocol_sim`) for the simulated bench.
    out_dir : the bundle directory. The data sets measured are added to an existing bundle
        (new file names; the previous calibration, pwm table and Rth summary are kept under
        ``superseded``). Raw logs of every session go to ``raw/``.
    progress : show a progress bar on stderr.
    actions : which procedures, in order: any of ``calibrate``, ``rth``, ``cooling``, ``pwm``.
    plan : the measurement plan (default: :data:`PLANS` for the board the device names).
    replace_names : listed data files that the new data sets of their section replace.
    wait : wait for another writer of the bundle instead of failing with BusyError.
    overrides : fields of :class:`Plan` to change, e.g. ``settle_s=60``.

    Returns
    -------
    Path
        The bundle directory.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "b"
    >>> path = run_bench("sim://actuator?seed=1", out, actions=["calibrate"],
    ...                  calibration_c=(25.0, 50.0), calibration_settle_s=60.0)
    >>> sorted(x.name for x in path.iterdir())
    ['bundle.json', 'calibration.csv', 'forward.csv', 'raw']
    """
    unknown = set(overrides) - set(Plan.__dataclass_fields__)
    if unknown:
        raise DataFormatError(f"run_bench: unknown plan fields {sorted(unknown)}")
    replace(plan or Plan(), **overrides)  # check the values before touching the bench
    return Session(url, Path(out_dir), plan, overrides, progress, replace_names,
                   wait).run(actions)
