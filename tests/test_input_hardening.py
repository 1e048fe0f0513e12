"""The remaining tracebacks and blocks of issue 18, item 5: seeds, non-regular inputs, unwritable outputs found
before the work, misleading messages. Each case: exit status != 0, one line (or click's usage error), no
Python traceback, nothing outside the folder touched."""

import pytest
from click.testing import CliRunner

from gyrodrift.cli import main
from gyrodrift.cpso import CPSOSolver, check_seed
from gyrodrift.errors import OptionError


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
    from gyrodrift.reproduce import reproduce, run_reproduction

    with pytest.raises(OptionError, match="seed must be an int >= 0, got -1"):
        run_reproduction(seed=-1)
    with pytest.raises(OptionError, match="seed must be an int >= 0, got -1"):
        reproduce("never-created", seed=-1)


# --- schema versions --------------------------------------------------------------------------------------


@pytest.mark.parametrize("version", [True, 1.0, "1", 4.0])
def test_a_schema_version_that_is_not_an_integer_is_named_as_such(tmp_path, version):
    """`"schema_version": true` was reported as a schema-1 file (True == 1 in Python); 4.0 was read as 4."""
    import json

    from gyrodrift.model_io import ModelFileError, load_model

    path = tmp_path / "m.json"
    path.write_text(json.dumps({"format": "gyrodrift-drift-model", "schema_version": version}))
    with pytest.raises(ModelFileError) as info:
        load_model(path)
    message = str(info.value)
    assert f"schema_version {version!r} is not supported" in message and "schema 1" not in message
    result = _run(["predict", tmp_path / "runs.csv", "--model", path])
    assert result.exit_code == 1 and f"schema_version {version!r} is not supported" in _error_line(result)
