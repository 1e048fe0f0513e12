"""Every TOML file a user gives (scenario, campaign, log format, noise model) is read by `gyrodrift.files.toml_input`:
hostile contents are one error of the reader's own class naming the file, never a Python exception."""

from __future__ import annotations

import pytest

from gyrodrift.errors import GyrodriftError
from gyrodrift.fleet.spec import CampaignError, load_campaign
from gyrodrift.ins.scenario import ScenarioError, load_scenario
from gyrodrift.logs.log_format import LogFormatError, load_log_format
from gyrodrift.procedure.noise import load_noise_file

READERS = [
    (load_scenario, ScenarioError),
    (load_campaign, CampaignError),
    (load_log_format, LogFormatError),
    (load_noise_file, GyrodriftError),
]

HOSTILE = [
    (b"[gyro]\narw_deg_rth = " + b"9" * 5000 + b"\n", "invalid TOML"),
    (b"[gyro]\nx = " + b"[" * 5000 + b"]" * 5000 + b"\n", "nested too deeply"),
    (b"[gyro\n", "invalid TOML"),
    (b'[gyro]\nname = "\xff\xfe"\n', "not UTF-8 text"),
    (b"# " + b"x" * (2 << 20) + b"\n", "bytes;"),
]


@pytest.mark.parametrize(("read", "error"), READERS, ids=lambda v: getattr(v, "__name__", ""))
@pytest.mark.parametrize(("content", "message"), HOSTILE, ids=["digits", "nesting", "syntax", "bytes", "size"])
def test_hostile_toml_is_one_error_naming_the_file(tmp_path, read, error, content, message):
    path = tmp_path / "input.toml"
    path.write_bytes(content)
    with pytest.raises(error) as info:
        read(path)
    assert isinstance(info.value, GyrodriftError)
    assert str(info.value).startswith(f"{path}: ") and message in str(info.value), str(info.value)


@pytest.mark.parametrize(("read", "error"), READERS, ids=lambda v: getattr(v, "__name__", ""))
def test_missing_file_and_directory(tmp_path, read, error):
    with pytest.raises(error, match="no such file"):
        read(tmp_path / "none.toml")
    with pytest.raises(error, match="a directory"):
        read(tmp_path)
