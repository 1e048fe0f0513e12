"""A manifest names only files of its own folder (issue 18, item 1).

A crafted (or received) results folder whose ``.gyrodrift-manifest.json`` names ``../victim.txt``, an absolute
path, a dotted or NUL-holding name, a symbolic link leading out, or whose pending journal maps such a name to a
temporary, is refused whole with one line naming the manifest and the entry, before any work; the victim is
untouched. A manifest of the wrong shape is one `OutputError` line, never an AttributeError/KeyError/TypeError.
"""

import hashlib
import json
import os

import pytest
from click.testing import CliRunner

from gyrodrift.cli import main
from gyrodrift.errors import OutputError
from gyrodrift.files.atomic import OutputFolder, check_complete
from gyrodrift.files.manifest import MANIFEST_NAME, UntrustedManifestError, read_manifest
from gyrodrift.files.recovery import finish_publication
from gyrodrift.files.temporaries import HOST, create_temporary

TOML = "[run]\nduration_h = 0.01\nrate_hz = 10.0\n"


def _describe(path):
    st = os.stat(path)
    return {"bytes": st.st_size, "mtime_ns": st.st_mtime_ns, "sha256": hashlib.sha256(path.read_bytes()).hexdigest()}


def _simulate(tmp_path, out):
    scenario = tmp_path / "t.toml"
    scenario.write_text(TOML)
    return CliRunner().invoke(main, ["simulate", str(scenario), "--out", str(out), "--quiet"])


def _edit(folder, change):
    path = folder / MANIFEST_NAME
    doc = json.loads(path.read_text())
    change(doc)
    path.write_text(json.dumps(doc))


def _assert_refused(result, *needles):
    assert result.exit_code == 1, result.output
    assert "Traceback" not in result.output
    assert result.exception is None or isinstance(result.exception, SystemExit)
    lines = result.output.strip().splitlines()
    assert len(lines) == 1, result.output
    assert MANIFEST_NAME in lines[0] and "refuses the whole of it" in lines[0]
    for needle in needles:
        assert needle in lines[0], lines[0]


@pytest.fixture
def sim(tmp_path):
    """A simulate output folder `d` and a victim file beside it."""
    out = tmp_path / "d"
    assert _simulate(tmp_path, out).exit_code == 0
    victim = tmp_path / "victim.txt"
    victim.write_text("precious\n")
    return out, victim


def test_the_issues_attack_a_relative_name_leading_out_is_refused_and_the_victim_kept(tmp_path, sim):
    out, victim = sim
    _edit(out, lambda doc: doc["sets"]["simulate"]["files"].update({"../victim.txt": _describe(victim)}))
    before = sorted(os.listdir(out))
    result = _simulate(tmp_path, out)
    _assert_refused(result, "'../victim.txt'", "path separator", "simulate")
    assert victim.read_text() == "precious\n"
    assert sorted(os.listdir(out)) == before  # no work done, nothing staged


def test_an_absolute_name_is_refused_and_the_victim_kept(tmp_path, sim):
    out, victim = sim
    _edit(out, lambda doc: doc["sets"]["simulate"]["files"].update({str(victim): _describe(victim)}))
    _assert_refused(_simulate(tmp_path, out), "absolute path")
    assert victim.read_text() == "precious\n"


def test_a_journal_mapping_a_name_outside_to_a_temporary_is_refused_and_the_victim_kept(tmp_path, sim):
    out, _ = sim
    victim2 = tmp_path / "victim2.txt"
    victim2.write_text("precious too\n")
    tmp = out / f".imu.parquet.gyrodrift-tmp-{HOST}-1-{'a' * 12}"
    tmp.write_bytes(b"attacker's bytes")
    entry = {**_describe(tmp), "tmp": tmp.name}

    def add_journal(doc):
        doc["pending"] = {"command": "simulate", "meta": {}, "files": {"../victim2.txt": entry}}

    _edit(out, add_journal)
    _assert_refused(_simulate(tmp_path, out), "the pending journal", "'../victim2.txt'")
    assert victim2.read_text() == "precious too\n"
    with pytest.raises(UntrustedManifestError, match="pending journal"):  # a reader of the folder refuses it too
        check_complete(out / "imu.parquet")


def test_a_journal_whose_temporary_names_another_file_or_leads_out_is_refused(tmp_path, sim):
    out, victim = sim
    for tmp in ("../victim.txt", f".other.gyrodrift-tmp-{HOST}-1-{'a' * 12}", "imu.parquet"):
        entry = {**_describe(out / "imu.parquet"), "tmp": tmp}

        def add_journal(doc, entry=entry):
            doc["pending"] = {"command": "simulate", "meta": {}, "files": {"imu.parquet": entry}}

        _edit(out, add_journal)
        _assert_refused(_simulate(tmp_path, out), '"tmp" is', "not a temporary of that file")
        del_pending = json.loads((out / MANIFEST_NAME).read_text())
        del del_pending["pending"]
        (out / MANIFEST_NAME).write_text(json.dumps(del_pending))
    assert victim.read_text() == "precious\n"


def test_a_symlink_leading_out_of_the_folder_is_refused_and_its_target_kept(tmp_path, sim):
    out, victim = sim
    (out / "imu.parquet").unlink()
    (out / "imu.parquet").symlink_to(victim)
    _edit(out, lambda doc: doc["sets"]["simulate"]["files"].update({"imu.parquet": _describe(victim)}))
    _assert_refused(_simulate(tmp_path, out), "'imu.parquet'", "symbolic link")
    assert victim.read_text() == "precious\n" and (out / "imu.parquet").is_symlink()


@pytest.mark.parametrize(
    ("name", "why"),
    [
        ("..", "not a file of the folder"),
        (".", "not a file of the folder"),
        (".hidden", "starts with a dot"),
        ("a\0b", "NUL"),
        ("sub/imu.parquet", "path separator"),
        ("sub\\imu.parquet", "path separator"),
        ("", "not a file name"),
        (MANIFEST_NAME, "starts with a dot"),
    ],
)
def test_every_name_that_is_not_a_plain_file_name_is_refused(tmp_path, name, why):
    folder = tmp_path / "d"
    folder.mkdir()
    entry = {"bytes": 1, "mtime_ns": 1, "sha256": "0" * 64}
    doc = {"format": "gyrodrift-manifest/1", "sets": {"truth": {"files": {name: entry}}}}
    (folder / MANIFEST_NAME).write_text(json.dumps(doc))
    with pytest.raises(UntrustedManifestError, match=why) as info:
        OutputFolder(folder, "truth", ["a.json"])
    message = str(info.value)
    assert "\n" not in message and message.startswith(str(folder / MANIFEST_NAME))


@pytest.mark.parametrize(
    ("doc", "why"),
    [
        ({"sets": []}, '"sets" is list, not a mapping'),
        ({"sets": {"truth": "x"}}, "the set 'truth' is str, not a mapping"),
        ({"sets": {"truth": {}}}, 'has "files" NoneType'),
        ({"sets": {"truth": {"files": ["a.json"]}}}, 'has "files" list'),
        ({"sets": {"truth": {"files": {"a.json": "x"}}}}, "is str, not a mapping"),
        ({"sets": {"truth": {"files": {"a.json": {"mtime_ns": 1, "sha256": "0" * 64}}}}}, '"bytes" is None'),
        ({"sets": {"truth": {"files": {"a.json": {"bytes": True, "mtime_ns": 1, "sha256": "0" * 64}}}}}, '"bytes"'),
        ({"sets": {"truth": {"files": {"a.json": {"bytes": -1, "mtime_ns": 1, "sha256": "0" * 64}}}}}, '"bytes"'),
        ({"sets": {"truth": {"files": {"a.json": {"bytes": 1, "mtime_ns": "1", "sha256": "0" * 64}}}}}, '"mtime_ns"'),
        ({"sets": {"truth": {"files": {"a.json": {"bytes": 1, "mtime_ns": 1, "sha256": 5}}}}}, '"sha256" is 5'),
        ({"sets": {}, "pending": []}, "the pending journal is list"),
        ({"sets": {}, "pending": {"command": 1, "meta": {}, "files": {}}}, '"command" 1'),
        ({"sets": {}, "pending": {"command": "truth", "meta": [], "files": {}}}, '"meta" list'),
        ({"sets": {}, "pending": {"command": "truth", "meta": {}, "files": "a.json"}}, '"files" str'),
    ],
)
def test_a_manifest_of_the_wrong_shape_is_one_output_error(tmp_path, doc, why):
    folder = tmp_path / "d"
    folder.mkdir()
    (folder / "a.json").write_text("x")
    (folder / MANIFEST_NAME).write_text(json.dumps({"format": "gyrodrift-manifest/1", **doc}))
    for reader in (
        lambda: OutputFolder(folder, "truth", ["a.json"]),
        lambda: check_complete(folder / "a.json"),
        lambda: finish_publication(folder, read_manifest(folder)),
    ):
        with pytest.raises(UntrustedManifestError) as info:
            reader()
        assert why in str(info.value) and "\n" not in str(info.value)
    assert (folder / "a.json").read_text() == "x"


def test_a_foreign_manifest_still_lets_a_reader_pass_and_a_fifo_manifest_is_refused_without_blocking(tmp_path):
    folder = tmp_path / "d"
    folder.mkdir()
    (folder / "a.json").write_text("x")
    (folder / MANIFEST_NAME).write_text('{"format": "someone-else/1"}')
    check_complete(folder / "a.json")  # not gyrodrift's manifest: the user's file is read as before
    (folder / MANIFEST_NAME).unlink()
    os.mkfifo(folder / MANIFEST_NAME)
    with pytest.raises(OutputError, match="is a FIFO, not a regular file"):
        OutputFolder(folder, "truth", ["a.json"])


def test_a_valid_manifest_with_a_journal_still_recovers(tmp_path):
    """The checks leave gyrodrift's own journals alone: a publication interrupted after its journal is finished."""
    folder = tmp_path / "d"
    with OutputFolder(folder, "truth", ["a.json"]).publish() as stage:
        stage.file("a.json").write_text("1")
    tmp = create_temporary(folder, "a.json")
    tmp.write_text("2")
    _edit(
        folder,
        lambda doc: doc.update(
            {"pending": {"command": "truth", "meta": {}, "files": {"a.json": {**_describe(tmp), "tmp": tmp.name}}}}
        ),
    )
    finish_publication(folder, read_manifest(folder))
    assert (folder / "a.json").read_text() == "2" and not tmp.exists()
    check_complete(folder / "a.json")


def test_navigate_into_a_folder_whose_manifest_names_an_absolute_path_keeps_the_victim(tmp_path, sim):
    """The issue's second case: an absolute name in another command's set, `navigate` into the folder."""
    out, victim = sim
    entry = _describe(victim)
    _edit(out, lambda doc: doc["sets"].update({"navigate": {"files": {str(victim): entry}}}))
    result = CliRunner().invoke(main, ["navigate", str(out / "imu.parquet"), "--out", str(out), "--quiet"])
    _assert_refused(result, "the set 'navigate'", "absolute path")
    assert victim.read_text() == "precious\n"
    assert sorted(os.listdir(out)) == [MANIFEST_NAME, "imu.parquet", "scenario.resolved.toml"]
