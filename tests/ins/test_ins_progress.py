"""The progress bar: silenced by quiet=True and whenever stderr is not a terminal."""

import io
import sys

from gyrodrift.progress import progress


class _Tty(io.StringIO):
    def isatty(self):
        return True


def test_quiet_and_non_tty_disable_the_bar(monkeypatch):
    monkeypatch.setattr(sys, "stderr", _Tty())
    with progress(10, "x", quiet=True) as bar:
        assert bar.disable
        bar.update(10)  # a disabled bar still accepts updates
    assert sys.stderr.getvalue() == ""

    monkeypatch.setattr(sys, "stderr", io.StringIO())  # not a terminal
    with progress(10, "x", quiet=False) as bar:
        assert bar.disable
    assert sys.stderr.getvalue() == ""


def test_bar_shows_on_a_terminal(monkeypatch):
    monkeypatch.setattr(sys, "stderr", _Tty())
    with progress(10, "simulate", quiet=False) as bar:
        assert not bar.disable
        bar.update(10)
    assert "simulate" in sys.stderr.getvalue()


def test_counts_are_integers_and_large_totals_scaled(monkeypatch):
    """Issue 22: a campaign's bar read ``1.00/4.00 run``; counts are integers, large totals take SI prefixes."""
    from gyrodrift.progress import SCALED_FROM

    monkeypatch.setattr(sys, "stderr", _Tty())
    with progress(4, "campaign", unit="run") as bar:
        bar.update(1)
        assert "| 1/4 [" in str(bar) and "1.00" not in str(bar)
    with progress(8 * SCALED_FROM, "simulate") as bar:
        bar.update(2 * SCALED_FROM)
        assert "| 20.0k/80.0k [" in str(bar)
