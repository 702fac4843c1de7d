"""``spicethermal compose PART.json [TIM.json] HEATSINK.json -o SYSTEM.json``: networks in
series as one model (:mod:`spicethermal.core.compose`): a device's junction-to-case (a
vendor's network from ``import``, or a fit), an interface, a heatsink or board to ambient.
Each model's reference is the next one's junction; only the last may end at the ambient.
A Foster model is converted exactly to Cauer first, and the command says so. Export the
result with ``spicethermal export SYSTEM.json`` (one ``.lib``).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ...core.compose import chain
from ...core.errors import DataFormatError
from ...model import ThermalModel

NAME = "compose"
HELP = ("chain thermal models in series (a part's junction-to-case, an interface, a heatsink to "
        "ambient) into one Cauer model with its Zth, exportable as one .lib")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("models", nargs="+", metavar="MODEL.json",
                        help="spicethermal-model files (/1 to /4), junction first: PART.json "
                             "[TIM.json ...] HEATSINK.json")
    parser.add_argument("-o", "--output", required=True, metavar="SYSTEM.json",
                        help="model file to write (spicethermal-model/3, Cauer)")


def run(args: argparse.Namespace) -> int:
    if len(args.models) < 2:
        raise DataFormatError("compose: give at least two models (a part and what it is "
                              "mounted on, e.g. PART.json HEATSINK.json)")
    models = [ThermalModel.load(p) for p in args.models]
    for k, (path, m) in enumerate(zip(args.models, models, strict=True)):
        if m.effects:
            raise DataFormatError(f"{path}: has effects ({', '.join(e.name for e in m.effects)}):"
                                  " compose chains linear networks only")
        if m.reference == "ambient" and k < len(models) - 1:
            raise DataFormatError(f"{path}: its reference is the ambient: only the last model "
                                  "of the chain may end at the ambient")
    out = chain([(m.ladder, m.case_c_j_per_k) for m in models])
    notes = [f"{Path(p).name}: Foster network converted exactly to Cauer (the same Zth with "
             "its reference held; its nodes are the equivalent ladder's)"
             for p, conv in zip(args.models, out.converted, strict=True) if conv]
    parts = [{"file": Path(p).name, "device": m.provenance.get("device", Path(p).stem),
              "topology": m.ladder.topology, "rth_k_per_w": m.rth,
              "case_c_j_per_k": m.case_c_j_per_k, "first_node": start}
             for p, m, start in zip(args.models, models, out.starts, strict=True)]
    first = models[0].provenance
    prov = {"device": first.get("device", Path(args.models[0]).stem),
            "source": " + ".join(Path(p).name for p in args.models),
            "compose": parts}
    if notes:
        prov["note"] = "; ".join(notes)
    system = ThermalModel(out.ladder, reference=models[-1].reference, provenance=prov,
                          case_c_j_per_k=out.case_c)
    path = system.save(args.output)
    print(f"wrote {path}: {' + '.join(str(p['device']) for p in parts)}, Cauer ladder of "
          f"{out.ladder.order} stages, Rth = {system.rth:.6g} K/W ({system.reference})")
    for note in notes:
        print(note)
    return 0
