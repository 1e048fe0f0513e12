"""The progress bar: silenced by quiet=True and whenever stderr is not a terminal; drawn on a terminal of any size."""

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


def _stderr_through_a_pty(columns: int) -> str:
    """What a child's progress bar writes to a pseudo-terminal of `columns` x 24 (0: the size a new pty has until
    someone sets one, as under ``script`` or ``docker exec -t`` without a size)."""
    import fcntl
    import os
    import pty
    import struct
    import subprocess
    import termios

    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24 if columns else 0, columns, 0, 0))
    code = (
        "from gyrodrift.progress import progress\n"
        "with progress(3, 'sized', unit='task') as bar:\n"
        "    for _ in range(3):\n"
        "        bar.refresh(); bar.update(1)\n"
    )
    child = subprocess.Popen([sys.executable, "-c", code], stderr=slave, stdout=subprocess.DEVNULL)
    os.close(slave)
    out = b""
    while True:
        try:
            data = os.read(master, 65536)
        except OSError:  # EIO: the child closed its end
            break
        if not data:
            break
        out += data
    os.close(master)
    assert child.wait(timeout=60) == 0
    return out.decode(errors="replace")


def test_bar_shows_on_a_terminal_that_reports_no_size():
    """tqdm draws nothing on a 0 x 0 terminal (its rows -1 hide every bar): the bar takes 80 x 24 there."""
    text = _stderr_through_a_pty(0)
    assert "sized:" in text and "1/3" in text and "2/3" in text, text
    assert max(len(line) for line in text.split("\r")) <= 80 + 4  # drawn at 80 columns (+ cursor codes)


def test_bar_follows_a_sized_terminal():
    text = _stderr_through_a_pty(50)
    assert "sized:" in text and "1/3" in text, text
    assert max(len(line) for line in text.split("\r")) <= 50 + 4
