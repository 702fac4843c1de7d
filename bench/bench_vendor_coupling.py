"""Vendor networks coupled to heatsinks: the exported Cauer (imported exactly, or fitted to the
vendor's case-held Zth as a user would) and the Foster export, against the exact solution of
the vendor network on the same heatsink (junction temperature error, % of the peak rise).

Targets (issue 15): fitted Cauer within 2 % (slow heatsink) and 5 % (heatsink time constant
among the device's). Run: .venv/bin/python bench/bench_vendor_coupling.py
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path
from types import SimpleNamespace

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from test_spice import coupled_error, ladder_branches  # noqa: E402
from test_vendor import NETWORKS, VENDOR, branches, vendor_zth  # noqa: E402

from spicethermal.fit.ladder import fit_model  # noqa: E402
from spicethermal.io.vendor import import_model  # noqa: E402
from spicethermal.spice import lib as spice  # noqa: E402


def main() -> None:
    pins = spice.Pins("TJ", "TC")
    cases = [("slow", "step"), ("slow", "pwm"), ("among", "step"), ("among", "pwm")]
    print(f"{'network':<14} {'model':<22} " + " ".join(f"{h + ' ' + d:>11}" for h, d in cases))
    worst: dict[str, float] = {}
    for (file, sub), (topology, r, c, case_c) in NETWORKS.items():
        if topology != "cauer":
            continue
        imported = import_model(VENDOR / file, sub)
        t = np.logspace(-6, 2, 81)
        curve = SimpleNamespace(t_s=t, zth_k_per_w=vendor_zth(topology, r, c, t),
                                rth_k_per_w=sum(r))
        fitted, res = fit_model(curve, reference="case")
        fit_err = np.max(np.abs(fitted.ladder.zth(t) - curve.zth_k_per_w)) / sum(r)
        rows = [("imported cauer", imported, "cauer", branches(r, c, case_c)),
                ("fitted cauer", fitted, "cauer", ladder_branches(r, c)),
                ("fitted cauer, case C", fitted, "cauer", branches(r, c, case_c)),
                ("fitted foster", fitted, "foster", ladder_branches(r, c))]
        with tempfile.TemporaryDirectory() as tmp:
            for label, model, topo, (rs, cs) in rows:
                lib = spice.export(model, Path(tmp) / "m.lib", "ngspice", topo, "M", pins=pins)
                errs = [coupled_error(lib, "M", pins, rs, cs, h, d) for h, d in cases]
                for (h, _), e in zip(cases, errs, strict=True):
                    worst[f"{label} {h}"] = max(worst.get(f"{label} {h}", 0.0), e)
                print(f"{sub:<14} {label:<22} " + " ".join(f"{100 * e:>10.3f}%" for e in errs))
        print(f"{'':<14} fit: order {res.order}, max |dZth| {100 * fit_err:.3f} % of Rth")
    print("worst:", ", ".join(f"{k} {100 * v:.2f} %" for k, v in worst.items()))


if __name__ == "__main__":
    main()
