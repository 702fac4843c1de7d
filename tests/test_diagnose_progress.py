"""diagnose shows one progress bar per step over the candidate fits, on a terminal only."""

from __future__ import annotations

import io
import sys

from spicethermal.analysis.diagnose import diagnose
from spicethermal.analysis.scenarios import scenario_bundle


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_diagnose_progress_on_a_terminal_only(monkeypatch):
    bundle = scenario_bundle("sample-window", seed=0)
    term = _Terminal()
    monkeypatch.setattr(sys, "stderr", term)
    d = diagnose(bundle, effects=["sample-window", "tsp-nonlinearity"], quiet=False)
    assert d.effects == ["sample-window"]
    assert "diagnose step 1: fitting effects" in term.getvalue() and "/2 " in term.getvalue()
    quiet = _Terminal()
    monkeypatch.setattr(sys, "stderr", quiet)
    diagnose(bundle, effects=["sample-window"], quiet=True)
    assert quiet.getvalue() == ""
    piped = io.StringIO()
    monkeypatch.setattr(sys, "stderr", piped)
    diagnose(bundle, effects=["sample-window"], quiet=False)
    assert piped.getvalue() == ""
