"""Progress on stderr: shown on a terminal, off with -q and off when stderr is not a terminal."""

from __future__ import annotations

import io
import sys

from spicethermal.progress import bar, enabled


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_bar_on_a_terminal_and_off_otherwise(monkeypatch):
    term = _Terminal()
    monkeypatch.setattr(sys, "stderr", term)
    assert enabled() and not enabled(quiet=True)
    assert list(bar(range(4), desc="points")) == [0, 1, 2, 3]
    assert "points" in term.getvalue() and "/4 " in term.getvalue()
    quiet = _Terminal()
    monkeypatch.setattr(sys, "stderr", quiet)
    assert list(bar(range(4), desc="points", quiet=True)) == [0, 1, 2, 3]
    assert quiet.getvalue() == ""
    piped = io.StringIO()  # not a terminal: nothing, whatever -q says
    monkeypatch.setattr(sys, "stderr", piped)
    assert not enabled() and list(bar(iter(range(2)), total=2)) == [0, 1]
    assert piped.getvalue() == ""
