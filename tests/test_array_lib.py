"""The N-port .lib of an array model, in the three dialects, checked in ngspice."""

from __future__ import annotations

import re

import pytest

from spicethermal.bench.array_devices import ArrayGeometry
from spicethermal.core.errors import DataFormatError
from spicethermal.spice.array_lib import check_array_lib, export_array, render_array_lib


@pytest.fixture(scope="module")
def cell():
    return ArrayGeometry().model()


def test_the_subcircuit_has_one_pin_per_cell_and_only_r_and_c(cell, tmp_path) -> None:
    path = export_array(cell, tmp_path / "braille.lib", "pspice", "BRAILLE8")
    text = path.read_text()
    assert ".SUBCKT BRAILLE8 TJ1 TJ2 TJ3 TJ4 TJ5 TJ6 TJ7 TJ8 TREF" in text
    assert "pspice dialect" in text and "TJ7: cell D7 at (0, 7.5) mm" in text
    body = text.split(".SUBCKT", 1)[1].splitlines()[1:-1]
    assert body and all(re.match(r"^[RC]\d+ ", line) for line in body)
    assert "limit(" not in text.lower()
    assert len([x for x in body if x.startswith("C")]) == len(cell.nodes)
    with pytest.raises(DataFormatError, match="dialect"):
        render_array_lib(cell, "spectre")
    with pytest.raises(DataFormatError, match="not allowed"):
        render_array_lib(cell, name="bad name")


@pytest.mark.ngspice
@pytest.mark.parametrize("dialect", ["ngspice", "pspice", "ltspice"])
def test_ngspice_reproduces_the_model_within_half_a_percent(cell, dialect) -> None:
    result = check_array_lib(cell, dialect, heated=[0, 4] if dialect != "ngspice" else None)
    assert result["max_error"] < 0.005
    assert result["runs"] == (8 if dialect == "ngspice" else 2)
