"""Every writing command against a read-only and a full output location, and the outputs it must refuse (issue 8).

For each command: exit status 1, one line naming the path and the reason, no traceback, no temporary left,
the previous outputs byte-identical. As root the location is a real tmpfs (remounted read-only, or filled to
the last byte); otherwise the failures are injected (EROFS when creating or renaming under the location,
ENOSPC from fsync). Standard output on a full device and a closed pipe run the real CLI in a subprocess.
"""

from __future__ import annotations

import contextlib
import errno
import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest
from click.testing import CliRunner

import gyrodrift
from gyrodrift.cli import main
from gyrodrift.files.manifest import MANIFEST_NAME
from gyrodrift.ins.scenario import Scenario
from gyrodrift.ins.simulate import simulate
from gyrodrift.ins.synthetic_fleet import simulate_fleet

PAPER_RUNS = Path(gyrodrift.__file__).parent / "data" / "paper_runs.csv"
READ_ONLY, FULL = "read-only file system", "no space left on the device"


@dataclass
class Inputs:
    folder: Path
    log: Path  # 16 h simulated run at 5 Hz
    static_log: Path  # 6 min without rotation (for allan)
    scenario: Path
    model: Path
    results: dict  # one real reproduction (tests/conftest.py's, seed 3), replayed by the reproduce command


def _run(*args, **kwargs):
    return CliRunner().invoke(main, [str(a) for a in args], **kwargs)


@pytest.fixture(scope="module")
def inputs(tmp_path_factory, paper_reproduction):
    folder = tmp_path_factory.mktemp("inputs")
    (log,), _ = simulate_fleet(folder / "fleet", 1, rate_hz=5.0)
    # 6 min at 10 Hz: 3600 samples, averaging times 0.1-102 s (11 points); what is checked here is where allan's
    # outputs go, not the noise it finds, and 0.5 h cost allan about twice the CPU
    static = {
        "run": {"duration_h": 0.1, "rate_hz": 10.0},
        "rotation": {"scheme": "none"},
        "gyro": {"arw_deg_rth": 0.001},
        "accel": {"vrw_ug_rthz": 10.0},
    }
    static_log = simulate(Scenario.from_dict(static), out_dir=folder / "static")
    scenario = folder / "short.toml"
    scenario.write_text("[run]\nduration_h = 0.02\nrate_hz = 10.0\n")
    model = folder / "model.json"
    fit = ["fit", PAPER_RUNS, "--lat0-deg", 28.222, "--split", "train", "--encoding", "temp_range", "--target", "drift"]
    r = _run(*fit, "--gamma", 10, "--sigma", 1, "--out", model)  # an encoding every command (export too) takes
    assert r.exit_code == 0, r.output
    return Inputs(folder, log, static_log, scenario, model, paper_reproduction[1])


# Each writing command: its arguments for an output location, and the file or folder it writes there.
COMMANDS = {
    "fit": lambda i, loc: (
        ["fit", PAPER_RUNS, "--lat0-deg", 28.222, "--split", "train", "--gamma", 10, "--sigma", 1]
        + ["--out", loc / "model.json"]
    ),
    "predict --out": lambda i, loc: (
        ["predict", PAPER_RUNS, "--model", i.model, "--lat0-deg", 28.222, "--split", "train", "--out", loc / "pred.csv"]
    ),
    "reproduce": lambda i, loc: ["reproduce", "--out", loc / "repro", "--quiet"],
    "simulate": lambda i, loc: ["simulate", i.scenario, "--out", loc / "sim", "--quiet"],
    "navigate": lambda i, loc: ["navigate", i.log, "--hours", 0.5, "--out", loc / "nav", "--quiet"],
    "features --curves": lambda i, loc: (
        ["features", i.log, "--out", loc / "runs.csv", "--curves", loc / "curves.csv", "--quiet"]
    ),
    "truth --out": lambda i, loc: ["truth", i.log, "--hours", 0.5, "--out", loc / "truth", "--quiet"],
    "evaluate": lambda i, loc: ["evaluate", i.log, "--drift-deg-h", 0.003, "--hours", 0.5, "--out", loc / "eval"],
    "identify --out": lambda i, loc: ["identify", i.log, "--model", i.model, "--out", loc / "ident", "--quiet"],
    "allan": lambda i, loc: ["allan", i.static_log, "--out", loc / "allan", "--quiet"],
    "export": lambda i, loc: ["export", "--model", i.model, "--lang", "c", "--out", loc / "export"],
}


def _command(inputs, name, loc):
    import gyrodrift.paper.reproduce

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(gyrodrift.paper.reproduce, "run_reproduction", lambda **kw: inputs.results)
        return _run(*COMMANDS[name](inputs, loc))


def _snapshot(loc):
    return {str(p.relative_to(loc)): p.read_bytes() for p in sorted(loc.rglob("*")) if p.is_file()}


def _temporaries(loc):
    return [str(p) for p in loc.rglob("*gyrodrift-tmp*")]


def _mount(loc):
    """Mount a 16 MiB tmpfs at `loc`; False if this process may not (not root, no mount)."""
    if not sys.platform.startswith("linux") or os.geteuid() != 0:
        return False
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=16m", "tmpfs", str(loc)], capture_output=True)
    return done.returncode == 0


@pytest.fixture(scope="module")
def previous(inputs, tmp_path_factory):
    """An output location holding every command's previous outputs: (location, snapshot, mounted)."""
    loc = tmp_path_factory.mktemp("location")
    mounted = _mount(loc)
    try:
        for name in COMMANDS:
            r = _command(inputs, name, loc)
            assert r.exit_code == 0, f"{name}: {r.output}"
        yield loc, _snapshot(loc), mounted
    finally:
        if mounted:
            subprocess.run(["umount", "-l", str(loc)], check=False)


def _assert_one_line_failure(r, name, reason, loc):
    assert r.exit_code == 1 and isinstance(r.exception, SystemExit), f"{name}: {r.exception!r}\n{r.output}"
    lines = [line for line in r.stderr.splitlines() if line.strip() and not line.startswith("warning: ")]
    assert len(lines) == 1, f"{name}: {r.stderr}"  # the error; warnings about the data may come before it
    assert lines[0].startswith("Error: ") and reason in lines[0] and str(loc) in lines[0], f"{name}: {lines[0]}"
    assert "Traceback" not in r.output


@contextlib.contextmanager
def _read_only(loc, mounted):
    if mounted:
        subprocess.run(["mount", "-o", "remount,ro", str(loc)], check=True)
        try:
            yield
        finally:
            subprocess.run(["mount", "-o", "remount,rw", str(loc)], check=True)
        return
    under = str(loc) + os.sep
    real = {name: getattr(os, name) for name in ("open", "mkdir", "replace", "rename", "unlink", "rmdir")}

    def refuse(name):
        def call(path, *args, **kwargs):
            writing = name != "open" or args[0] & (os.O_CREAT | os.O_WRONLY | os.O_RDWR)
            if writing and os.path.abspath(os.fspath(path)).startswith(under):
                raise OSError(errno.EROFS, os.strerror(errno.EROFS), os.fspath(path))
            return real[name](path, *args, **kwargs)

        return call

    with pytest.MonkeyPatch.context() as mp:
        for name in real:
            mp.setattr(os, name, refuse(name))
        yield


@contextlib.contextmanager
def _full(loc, mounted):
    if mounted:
        filler = loc / "filler"
        with open(filler, "wb", buffering=0) as fh:
            for block in (1 << 16, 1 << 12, 1):  # to the last byte
                with contextlib.suppress(OSError):
                    while True:
                        fh.write(b"\0" * block)
        try:
            yield
        finally:
            filler.unlink()
        return
    real_fsync = os.fsync

    def fsync(fd):
        try:
            target = os.readlink(f"/proc/self/fd/{fd}")
        except OSError:
            target = ""
        if target.startswith(str(loc)):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real_fsync(fd)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(os, "fsync", fsync)
        yield


@pytest.mark.parametrize("where, reason", [(_read_only, READ_ONLY), (_full, FULL)], ids=["read-only", "full"])
def test_every_writing_command_fails_in_one_line_and_keeps_the_previous_outputs(inputs, previous, where, reason):
    loc, before, mounted = previous
    with where(loc, mounted):
        for name in COMMANDS:
            r = _command(inputs, name, loc)
            _assert_one_line_failure(r, name, reason, loc)
            assert _temporaries(loc) == [], name
            after = _snapshot(loc)
            after.pop("filler", None)
            assert after == before, f"{name} changed the previous outputs"


# --- outputs refused before any work -----------------------------------------------------------------------------


def _refused(r, *fragments):
    assert r.exit_code == 1 and isinstance(r.exception, SystemExit), f"{r.exception!r}\n{r.output}"
    lines = [line for line in r.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and all(f in lines[0] for f in fragments), r.stderr
    return lines[0]


def test_an_output_that_is_an_input_is_refused_and_the_input_kept(inputs, tmp_path):
    runs = tmp_path / "r.csv"
    runs.write_bytes(PAPER_RUNS.read_bytes())
    model = tmp_path / "m.json"
    model.write_bytes(inputs.model.read_bytes())
    fit = ["fit", runs, "--lat0-deg", 28.222, "--gamma", 10, "--sigma", 1, "--out"]
    _refused(_run(*fit, runs), "r.csv: is also an input of this command")
    (tmp_path / "link.csv").symlink_to(runs)
    _refused(_run(*fit, tmp_path / "link.csv"), "is also an input")
    for out in (model, runs):
        _refused(_run("predict", runs, "--model", model, "--lat0-deg", 28.222, "--out", out), "is also an input")
    log = tmp_path / "x.parquet"
    os.link(inputs.log, log)
    _refused(_run("features", log, "--out", log, "--quiet"), "x.parquet: is also an input")
    curves = ["features", log, "--out", tmp_path / "t.csv", "--curves", tmp_path / "t.csv", "--quiet"]
    _refused(_run(*curves), "t.csv: is also", "give two different files")
    assert runs.read_bytes() == PAPER_RUNS.read_bytes() and model.read_bytes() == inputs.model.read_bytes()
    assert log.read_bytes() == inputs.log.read_bytes() and not (tmp_path / "t.csv").exists()


def test_devices_fifos_folders_and_foreign_files_are_refused(inputs, tmp_path):
    fit = ["fit", PAPER_RUNS, "--lat0-deg", 28.222, "--gamma", 10, "--sigma", 1, "--out"]
    _refused(_run(*fit, "/proc/version"), "/proc/version: exists and is not a model file written by gyrodrift")
    (tmp_path / "dir.csv").mkdir()
    predict = ["predict", PAPER_RUNS, "--model", inputs.model, "--lat0-deg", 28.222, "--out"]
    _refused(_run(*predict, tmp_path / "dir.csv"), "dir.csv: is a directory")
    os.mkfifo(tmp_path / "fifo")
    _refused(_run(*predict, tmp_path / "fifo"), "fifo: is a FIFO")
    assert (tmp_path / "fifo").is_fifo()
    with contextlib.suppress(PermissionError, OSError):  # our own /dev/full (root only)
        os.mknod(tmp_path / "full", 0o666 | 0o020000, os.makedev(1, 7))
        _refused(_run(*fit, tmp_path / "full"), "full: is a device")
        assert (tmp_path / "full").is_char_device()
    (tmp_path / "notes.json").write_text("my notes\n")
    _refused(_run(*fit, tmp_path / "notes.json"), "notes.json: exists and is not a model file written by gyrodrift")
    assert (tmp_path / "notes.json").read_text() == "my notes\n"
    assert [p.name for p in tmp_path.iterdir() if "gyrodrift-tmp" in p.name] == []


def test_a_symlinked_model_file_is_followed_and_the_link_kept(inputs, tmp_path):
    (tmp_path / "models").mkdir()
    target = tmp_path / "models" / "m.json"
    target.write_bytes(inputs.model.read_bytes())
    (tmp_path / "current.json").symlink_to(target)
    r = _run("fit", PAPER_RUNS, "--lat0-deg", 28.222, "--gamma", 3, "--sigma", 2, "--out", tmp_path / "current.json")
    assert r.exit_code == 0, r.output
    assert (tmp_path / "current.json").is_symlink() and '"gamma": 3' in target.read_text().replace("3.0", "3")


def test_folders_holding_the_users_files_are_refused_and_the_current_folder_works(inputs, tmp_path, monkeypatch):
    import gyrodrift.paper.reproduce

    monkeypatch.setattr(gyrodrift.paper.reproduce, "run_reproduction", lambda **kw: inputs.results)
    (tmp_path / "d").mkdir()
    (tmp_path / "d" / "notes.txt").write_text("x")
    _refused(_run("reproduce", "--out", tmp_path / "d", "--quiet"), "holds files gyrodrift did not write", "notes.txt")
    user = tmp_path / "logs"
    user.mkdir()
    os.link(inputs.log, user / "run.parquet")
    (user / "notes.txt").write_text("x")
    _refused(_run("truth", user / "run.parquet", "--out", user, "--quiet"), "holds files gyrodrift did not write")
    assert sorted(p.name for p in user.iterdir()) == ["notes.txt", "run.parquet"]
    here = tmp_path / "here"
    here.mkdir()
    monkeypatch.chdir(here)
    for _ in range(2):  # into its own previous output too
        r = _run("reproduce", "--out", ".", "--quiet")
        assert r.exit_code == 0, r.output
    assert sorted(os.listdir(here)) == sorted([MANIFEST_NAME, "results.json", "report.md", "report.html"] + PNGS)
    assert sorted(os.listdir(tmp_path)) == ["d", "here", "logs"]  # no ..<hex>.tmp folder beside it


PNGS = ["fitness_curve.png", "pred_vs_true.png", "error_per_run.png", "position_error_72h.png"]


def test_navigate_into_the_simulation_folder_keeps_its_input(inputs, tmp_path):
    sim = tmp_path / "sim"
    assert _run("simulate", inputs.scenario, "--out", sim, "--quiet").exit_code == 0
    imu = (sim / "imu.parquet").read_bytes()
    for _ in range(2):
        r = _run("navigate", sim / "imu.parquet", "--out", sim, "--quiet")
        assert r.exit_code == 0, r.output
    assert (sim / "imu.parquet").read_bytes() == imu
    assert sorted(os.listdir(sim)) == [
        MANIFEST_NAME,
        "imu.parquet",
        "nav.parquet",
        "scenario.resolved.toml",
        "summary.json",
    ]
    _refused(_run("navigate", sim / "nav.parquet", "--out", sim, "--quiet"), "would replace an input")


# --- standard output ---------------------------------------------------------------------------------------------


def _gyrodrift(*args, **kwargs):
    code = "import sys; from gyrodrift.cli import main; sys.exit(main())"
    return subprocess.Popen([sys.executable, "-c", code, *map(str, args)], stderr=subprocess.PIPE, **kwargs)


def test_stdout_on_a_full_device_is_one_line(inputs, tmp_path):
    device = Path("/dev/full")
    if not device.is_char_device():
        try:
            os.mknod(tmp_path / "full", 0o666 | 0o020000, os.makedev(1, 7))
        except (PermissionError, OSError):
            pytest.skip("no full device")
        device = tmp_path / "full"
    commands = [  # predict writes its table itself; fit's summary line goes through click.echo
        ["predict", PAPER_RUNS, "--model", inputs.model, "--lat0-deg", 28.222, "--split", "train"],
        ["fit", PAPER_RUNS, "--lat0-deg", 28.222, "--split", "train", "--gamma", 10, "--sigma", 1]
        + ["--out", tmp_path / "m.json"],
    ]
    for args in commands:
        with open(device, "w") as out:
            proc = _gyrodrift(*args, stdout=out)
            err = proc.communicate(timeout=60)[1].decode()
        assert proc.returncode == 1, (args[0], err)
        assert err.strip() == "Error: standard output: no space left on the device", (args[0], err)


def test_stdout_closed_by_its_reader_ends_quietly(inputs):
    proc = _gyrodrift("predict", PAPER_RUNS, "--model", inputs.model, "--lat0-deg", 28.222, stdout=subprocess.PIPE)
    proc.stdout.close()  # | head -0
    err = proc.communicate(timeout=60)[1].decode()
    assert proc.returncode == 1 and "Traceback" not in err and "Exception ignored" not in err, err


def test_a_log_whose_simulation_was_interrupted_is_refused_until_simulate_runs_again(inputs, tmp_path, monkeypatch):
    import gyrodrift.files.atomic as atomic

    sim = tmp_path / "sim"
    assert _run("simulate", inputs.scenario, "--out", sim, "--quiet").exit_code == 0
    real_replace = os.replace

    class Killed(BaseException):  # SIGKILL between the two renames: nothing runs after it
        pass

    def replace(src, dst):
        if str(dst).endswith("scenario.resolved.toml"):
            raise Killed
        real_replace(src, dst)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(atomic.os, "replace", replace)
        mp.setattr(atomic, "finish_publication", lambda folder, manifest: manifest)
        mp.setattr(atomic.Stage, "_discard", lambda self: None)
        seeded = inputs.scenario.read_text().replace("[run]\n", "[run]\nseed = 7\n")
        (tmp_path / "s7.toml").write_text(seeded)
        with pytest.raises(Killed):
            _run("simulate", tmp_path / "s7.toml", "--out", sim, "--quiet", catch_exceptions=False)
    _refused(_run("navigate", sim / "imu.parquet", "--out", tmp_path / "nav", "--quiet"), "unfinished output")
    assert _run("simulate", inputs.scenario, "--out", sim, "--quiet").exit_code == 0
    assert _run("navigate", sim / "imu.parquet", "--out", tmp_path / "nav", "--quiet").exit_code == 0
    assert _temporaries(sim) == []
