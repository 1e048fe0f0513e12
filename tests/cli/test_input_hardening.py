"""The remaining tracebacks and blocks of issue 18, item 5: seeds, non-regular inputs, unwritable outputs found
before the work, misleading messages. Each case: exit status != 0, one line (or click's usage error), no
Python traceback, nothing outside the folder touched."""

import contextlib
import os
import signal
from pathlib import Path

import pytest
from click.testing import CliRunner

from gyrodrift.cli import main
from gyrodrift.drift_law import DriftLaw
from gyrodrift.errors import InputError, OptionError
from gyrodrift.learn.cpso import CPSOSolver, check_seed


def _run(args):
    result = CliRunner().invoke(main, [str(a) for a in args])
    assert "Traceback" not in result.output, result.output
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(result.exception)
    return result


def _error_line(result):
    """The one line of an error: the 'Error: ...' line (click's usage errors add their 'Usage:' lines)."""
    errors = [line for line in result.output.splitlines() if line.startswith("Error:")]
    assert len(errors) == 1, result.output
    return errors[0]


# --- seeds ------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "args",
    [
        ["fit", "runs.csv", "--out", "m.json"],
        ["reproduce", "--out", "r"],
        ["simulate", "t.toml", "--out", "d"],
        ["study", ".", "--out", "s"],
    ],
)
@pytest.mark.parametrize("seed", ["-1", "18446744073709551616", "1.5", "true"])
def test_every_seed_option_refuses_what_is_not_an_integer_in_0_to_2_64(tmp_path, monkeypatch, args, seed):
    monkeypatch.chdir(tmp_path)
    result = _run([*args, "--seed", seed])
    assert result.exit_code == 2
    assert "Invalid value for '--seed'" in _error_line(result)
    assert sorted(p.name for p in tmp_path.iterdir()) == []  # nothing written, nothing read


def test_a_library_seed_is_an_int_at_least_zero():
    assert check_seed(0) == 0 and check_seed(None) is None
    for bad in (-1, True, 1.5, "3"):
        with pytest.raises(OptionError, match="seed must be an int >= 0"):
            check_seed(bad)
    with pytest.raises(OptionError, match="rng must be an int >= 0, got -1"):
        CPSOSolver(lambda x: 0.0, [(0.0, 1.0)], rng=-1)
    from gyrodrift.paper.reproduce import reproduce, run_reproduction

    with pytest.raises(OptionError, match="seed must be an int >= 0, got -1"):
        run_reproduction(seed=-1)
    with pytest.raises(OptionError, match="seed must be an int >= 0, got -1"):
        reproduce("never-created", seed=-1)


# --- schema versions --------------------------------------------------------------------------------------


@pytest.mark.parametrize("version", [True, 1.0, "1", 4.0])
def test_a_schema_version_that_is_not_an_integer_is_named_as_such(tmp_path, version):
    """`"schema_version": true` was reported as a schema-1 file (True == 1 in Python); 4.0 was read as 4."""
    import json

    from gyrodrift.learn.model_io import ModelFileError, load_model

    path = tmp_path / "m.json"
    path.write_text(json.dumps({"format": "gyrodrift-drift-model", "schema_version": version}))
    with pytest.raises(ModelFileError) as info:
        load_model(path)
    message = str(info.value)
    assert f"schema_version {version!r} is not supported" in message and "schema 1" not in message
    result = _run(["predict", tmp_path / "runs.csv", "--model", path])
    assert result.exit_code == 1 and f"schema_version {version!r} is not supported" in _error_line(result)


# --- inputs that are not regular files ----------------------------------------------------------------------

# Every input a command reads, with X in its place (other inputs may be missing: the type refuses X first).
INPUTS = {
    "simulate SCENARIO": ["simulate", "X", "--out", "o"],
    "fit DATA": ["fit", "X", "--out", "o.json"],
    "predict DATA": ["predict", "X", "--model", "m.json"],
    "predict --model": ["predict", "r.csv", "--model", "X"],
    "export --model": ["export", "--model", "X", "--out", "o"],
    "navigate LOG": ["navigate", "X", "--out", "o"],
    "navigate --format": ["navigate", "l.csv", "--format", "X", "--out", "o"],
    "features LOGS": ["features", "l.parquet", "X", "--out", "o.csv"],
    "truth LOG": ["truth", "X"],
    "truth --noise": ["truth", "l.parquet", "--noise", "X"],
    "evaluate LOG": ["evaluate", "X", "--model", "m.json", "--out", "o"],
    "evaluate --model": ["evaluate", "l.parquet", "--model", "X", "--out", "o"],
    "evaluate --reference": ["evaluate", "l.parquet", "--model", "m.json", "--reference", "X", "--out", "o"],
    "identify LOG": ["identify", "X", "--model", "m.json"],
    "identify --model": ["identify", "l.parquet", "--model", "X"],
    "allan LOG": ["allan", "X", "--out", "o"],
    "campaign SOURCE": ["campaign", "X", "--out", "o"],
}


@pytest.fixture
def specials(tmp_path):
    """A FIFO, a listening socket's path, a directory, and the two endless devices."""
    import socket

    os.mkfifo(tmp_path / "fifo")
    sock = socket.socket(socket.AF_UNIX)
    sock.bind(str(tmp_path / "sock"))
    (tmp_path / "dir").mkdir()
    yield {
        "fifo": (tmp_path / "fifo", "is a FIFO, not a regular file"),
        "socket": (tmp_path / "sock", "is a socket, not a regular file"),
        "dev/zero": (Path("/dev/zero"), "is a device, not a regular file"),
        "dev/urandom": (Path("/dev/urandom"), "is a device, not a regular file"),
        "directory": (tmp_path / "dir", "is a directory; expected a file"),
    }
    sock.close()


@contextlib.contextmanager
def _deadline(seconds):
    """Fail instead of hanging for ever (a FIFO read blocks until someone writes)."""

    def alarm(signum, frame):
        raise TimeoutError(f"blocked for {seconds} s")

    old = signal.signal(signal.SIGALRM, alarm)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


@pytest.mark.parametrize("command", list(INPUTS))
def test_every_input_refuses_devices_fifos_sockets_and_folders_before_any_work(
    tmp_path, monkeypatch, specials, command
):
    monkeypatch.chdir(tmp_path)
    for kind, (path, reason) in specials.items():
        if kind == "directory" and command == "campaign SOURCE":
            continue  # a campaign folder is a valid source
        args = [str(path) if a == "X" else a for a in INPUTS[command]]
        with _deadline(30):
            result = _run(args)
        assert result.exit_code == 2, (kind, result.output)
        line = _error_line(result)
        assert "Invalid value for" in line and f"{path} {reason}" in line, (kind, line)
        assert not (tmp_path / "o").exists() and not (tmp_path / "o.csv").exists()
    assert (tmp_path / "fifo").is_fifo()


def test_a_study_folder_that_is_a_fifo_or_a_file_is_refused(tmp_path, specials):
    for path in (specials["fifo"][0], Path("/dev/zero")):
        result = _run(["study", path, "--out", tmp_path / "s"])
        assert result.exit_code == 2 and f"{path} is not a folder" in _error_line(result)


@pytest.mark.parametrize("kind", ["fifo", "dev/zero", "dev/urandom", "directory"])
def test_read_toml_refuses_non_regular_files_without_reading_them(kind, specials):
    from gyrodrift.files.toml_input import read_toml

    path, _ = specials[kind]
    with _deadline(30), pytest.raises(ValueError, match=r"is a (FIFO|device|directory), not a regular file"):
        read_toml(path, ValueError, expected="a scenario TOML file")


def test_read_toml_reads_at_most_its_limit_plus_one_byte(tmp_path, monkeypatch):
    """An oversized file is refused after reading max_bytes + 1 bytes, not all of it."""
    from gyrodrift.files import input_files
    from gyrodrift.files.toml_input import read_toml

    path = tmp_path / "big.toml"
    path.write_bytes(b"#" * 10_000)
    seen = []
    real_read = os.read
    monkeypatch.setattr(input_files.os, "read", lambda fd, n: seen.append(n) or real_read(fd, n))
    with pytest.raises(ValueError, match="more than 100 bytes; a scenario holds at most 100"):
        read_toml(path, ValueError, expected="a scenario", max_bytes=100)
    assert sum(seen) == 101


# --- an output location that cannot be written is found before the work -----------------------------------------


@pytest.fixture
def unwritable(tmp_path):
    """(a folder nothing can be written in, the reason the message gives): a read-only tmpfs as root, else a
    folder without write permission."""
    import subprocess
    import sys

    loc = tmp_path / "ro"
    loc.mkdir()
    if sys.platform.startswith("linux") and os.geteuid() == 0:
        mount = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1m,ro", "tmpfs", str(loc)], capture_output=True)
        if mount.returncode != 0:
            pytest.skip("root without mount: no unwritable folder to test with")
        try:
            yield loc, "read-only file system"
        finally:
            subprocess.run(["umount", "-l", str(loc)], check=False)
        return
    loc.chmod(0o555)
    try:
        yield loc, "permission denied"
    finally:
        loc.chmod(0o755)


def test_an_unwritable_output_location_is_refused_before_the_work(tmp_path, monkeypatch, unwritable):
    """`reproduce --out` under a read-only parent failed after 751 s of work; now every writer checks first."""
    import gyrodrift.paper.reproduce

    loc, reason = unwritable
    work = []
    monkeypatch.setattr(gyrodrift.paper.reproduce, "run_reproduction", lambda **kw: work.append(kw) or {})
    scenario = tmp_path / "t.toml"
    scenario.write_text("[run]\nduration_h = 0.01\nrate_hz = 10.0\n")
    runs = tmp_path / "runs.csv"
    runs.write_text("run,drift_deg_h\n")  # never read: the output is checked first
    cases = {
        "reproduce": (["reproduce", "--out", loc / "repro"], f"{loc / 'repro'}: cannot be created in {loc}"),
        "reproduce --out LOC": (["reproduce", "--out", loc], f"{loc}: cannot be written"),
        "simulate": (["simulate", scenario, "--out", loc / "a" / "b"], f"{loc / 'a' / 'b'}: cannot be created in"),
        "fit": (["fit", runs, "--out", loc / "m.json"], f"{loc / 'm.json'}: cannot be written"),
    }
    for name, (args, where) in cases.items():
        result = _run(args)
        assert result.exit_code == 1, (name, result.output)
        line = _error_line(result)
        assert where in line and line.endswith(reason), (name, line)
    assert work == [] and sorted(os.listdir(loc)) == []


# --- a drift to compensate is a drift -----------------------------------------------------------------------


@pytest.mark.parametrize("value", ["1e308", "-101", "nan", "inf"])
@pytest.mark.parametrize("command", ["navigate", "evaluate"])
def test_drift_deg_h_is_checked_with_its_option_name_and_a_stated_bound(tmp_path, command, value):
    """`navigate --drift-deg-h 1e308` named the core's gyro_bias_rad_s and showed the log's x/y biases."""
    scenario = tmp_path / "t.toml"
    scenario.write_text("[run]\nduration_h = 0.01\nrate_hz = 10.0\n")
    assert _run(["simulate", scenario, "--out", tmp_path / "sim", "--quiet"]).exit_code == 0
    result = _run([command, tmp_path / "sim" / "imu.parquet", f"--drift-deg-h={value}", "--out", tmp_path / "o"])
    assert result.exit_code == 2
    line = _error_line(result)
    assert "'--drift-deg-h'" in line and "gyro_bias" not in line, line
    if value in ("1e308", "-101"):
        assert "is not in [-100, 100] deg/h: an axial gyro drift" in line
    assert not (tmp_path / "o").exists()


def test_the_library_refuses_a_drift_beyond_the_bound_by_the_options_name(tmp_path):
    from gyrodrift.procedure import navigate

    scenario = tmp_path / "t.toml"
    scenario.write_text("[run]\nduration_h = 0.01\nrate_hz = 10.0\n")
    assert _run(["simulate", scenario, "--out", tmp_path / "sim", "--quiet"]).exit_code == 0
    for bad in (1e308, -100.5):
        with pytest.raises(OptionError, match=r"eps_ref_deg_h \(--drift-deg-h\) must be a finite drift within \+-100"):
            navigate(tmp_path / "sim" / "imu.parquet", drift_law=DriftLaw.constant(bad))
    with pytest.raises(InputError, match="drift law: eps_ref_deg_h must be a finite number, got nan"):
        DriftLaw.constant(float("nan"))


@pytest.mark.parametrize("kind", ["fifo", "dev/zero", "socket"])
def test_the_library_readers_of_run_tables_and_models_refuse_non_regular_files(kind, specials):
    """Without the CLI's type: `read_runs_csv` and `load_model` read through `read_limited` too."""
    from gyrodrift.learn.model_io import ModelFileError, load_model
    from gyrodrift.runs.table import RunTableError, read_runs_csv

    path, reason = specials[kind]
    with _deadline(30):
        with pytest.raises(RunTableError, match=reason):
            read_runs_csv(path)
        with pytest.raises(ModelFileError, match=reason):
            load_model(path)
