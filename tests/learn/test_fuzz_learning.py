"""Fuzzing the learning side's loaders (issue 8): any bytes or mutated valid file give a result or the package's
error (RunTableError, ModelFileError), never another exception. Few examples, no deadline: fast."""

import json

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gyrodrift.learn.drift_model import DriftModel, fit_drift_model
from gyrodrift.learn.model_io import ModelFileError, load_model, model_to_dict
from gyrodrift.runs.datasets import load_paper, paper_csv_path
from gyrodrift.runs.table import RunTable, RunTableError, read_runs_csv

FUZZ = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])

VALID_CSV = paper_csv_path().read_bytes()


def _read_table(tmp_path, data: bytes):
    path = tmp_path / "runs.csv"
    path.write_bytes(data)
    try:
        return read_runs_csv(path, lat0_deg=28.222)
    except RunTableError:
        return None


def _mutate(data: bytes, edits) -> bytes:
    out = bytearray(data)
    for pos, kind, payload in edits:
        i = pos % (len(out) + 1)
        if kind == 0:
            out[i:i] = payload
        elif kind == 1:
            del out[i : i + len(payload)]
        else:
            out[i : i + len(payload)] = payload
    return bytes(out)


EDITS = st.lists(
    st.tuples(st.integers(0, 10**6), st.integers(0, 2), st.binary(min_size=1, max_size=8)), min_size=1, max_size=6
)
TOKENS = st.sampled_from(
    [b",", b"\n", b"\r", b'"', b"~", b"nan", b"inf", b"-1e309", b"9" * 500, b"\x00", b"\xff", b"\xef\xbb\xbf", b""]
)


@FUZZ
@given(data=st.binary(max_size=400))
def test_any_bytes_give_a_run_table_or_its_error(tmp_path, data):
    result = _read_table(tmp_path, data)
    assert result is None or isinstance(result, RunTable)


@FUZZ
@given(edits=EDITS)
def test_mutated_valid_run_table_gives_a_table_or_its_error(tmp_path, edits):
    result = _read_table(tmp_path, _mutate(VALID_CSV, edits))
    assert result is None or isinstance(result, RunTable)


@FUZZ
@given(pos=st.lists(st.integers(0, 10**6), min_size=1, max_size=4), tokens=st.lists(TOKENS, min_size=1, max_size=4))
def test_valid_run_table_with_hostile_tokens_gives_a_table_or_its_error(tmp_path, pos, tokens):
    edits = [(p, 2, t or b" ") for p, t in zip(pos, tokens, strict=False)]
    result = _read_table(tmp_path, _mutate(VALID_CSV, edits))
    assert result is None or isinstance(result, RunTable)


@pytest.fixture(scope="module")
def model_text():
    model = fit_drift_model(load_paper().train.select(slice(0, 8)), gamma=10.0, sigma=1.0)
    return json.dumps(model_to_dict(model))


def _load(tmp_path, text: str | bytes):
    path = tmp_path / "model.json"
    path.write_bytes(text.encode("utf-8", "surrogatepass") if isinstance(text, str) else text)
    try:
        return load_model(path)
    except ModelFileError:
        return None


@FUZZ
@given(edits=EDITS)
def test_mutated_model_file_bytes_give_a_model_or_its_error(tmp_path, model_text, edits):
    result = _load(tmp_path, _mutate(model_text.encode(), edits))
    assert result is None or isinstance(result, DriftModel)


JSON_VALUES = st.recursive(
    st.none()
    | st.booleans()
    | st.integers(-(10**500), 10**500)
    | st.floats(allow_nan=True, allow_infinity=True)
    | st.text(max_size=5),
    lambda children: st.lists(children, max_size=3) | st.dictionaries(st.text(max_size=4), children, max_size=3),
    max_leaves=6,
)


def _paths(doc, prefix=()):
    """Every (container, key) pair of a JSON document."""
    if isinstance(doc, dict):
        for k, v in doc.items():
            yield doc, k
            yield from _paths(v, prefix + (k,))
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            yield doc, i
            yield from _paths(v, prefix + (i,))


@FUZZ
@given(data=st.data())
def test_model_file_with_values_replaced_or_removed_gives_a_model_or_its_error(tmp_path, model_text, data):
    doc = json.loads(model_text)
    for _ in range(data.draw(st.integers(1, 3))):
        places = list(_paths(doc))
        container, key = places[data.draw(st.integers(0, len(places) - 1))]
        if data.draw(st.booleans()) and isinstance(container, dict):
            del container[key]
        else:
            container[key] = data.draw(JSON_VALUES)
    text = json.dumps(doc, allow_nan=True)
    result = _load(tmp_path, text)
    assert result is None or isinstance(result, DriftModel)
