"""Model files: exact round trip, and clear errors for anything that is not a valid model file."""

import json

import numpy as np
import pytest

from gyrodrift.datasets import load_paper
from gyrodrift.model import fit_drift_model, training_digest
from gyrodrift.model_io import ModelFileError, load_model, model_to_dict, save_model


@pytest.fixture(scope="module")
def paper():
    return load_paper()


@pytest.mark.parametrize("scaling", ["standard", "minmax", "none"])
@pytest.mark.parametrize("encoding", ["temp_range", "temp_span"])
def test_round_trip_reproduces_predictions_to_the_bit(tmp_path, paper, scaling, encoding):
    model = fit_drift_model(paper.train, encoding=encoding, scaling=scaling, gamma=50.0, sigma=1.3)
    path = tmp_path / "model.json"
    save_model(model, path)
    again = load_model(path)
    np.testing.assert_array_equal(again.predict(paper.test), model.predict(paper.test))
    doc = json.loads(path.read_text())
    assert doc["schema_version"] == 1 and doc["encoding"] == encoding
    assert doc["training"]["sha256"] == training_digest(paper.train)
    assert len(doc["lssvr"]["alpha"]) == 22


def test_tuned_model_keeps_its_tuning_record(tmp_path, paper):
    model = fit_drift_model(paper.train, method="grid", rng=0)
    save_model(model, tmp_path / "m.json")
    again = load_model(tmp_path / "m.json")
    assert again.tuning.method == "grid" and again.tuning.gamma == model.lssvr.gamma


def test_digest_changes_with_the_data(paper):
    assert training_digest(paper.train) != training_digest(paper.test)
    assert training_digest(paper.train) == training_digest(load_paper().train)


@pytest.fixture
def good_doc(paper):
    return model_to_dict(fit_drift_model(paper.train, gamma=10.0, sigma=1.0))


@pytest.mark.parametrize(
    "mutate, message",
    [
        (lambda d: d.update(format="other"), "not a gyrodrift model file"),
        (lambda d: d.update(schema_version=99), "schema_version 99 is not supported"),
        (lambda d: d.pop("lssvr"), "missing key 'lssvr'"),
        (lambda d: d.update(encoding="weird"), "unknown encoding 'weird'"),
        (lambda d: d["lssvr"].update(alpha=d["lssvr"]["alpha"][:-1]), "key 'alpha' has shape"),
        (lambda d: d["lssvr"].update(sigma=-1.0), "sigma"),
        (lambda d: d["lssvr"]["support_vectors"][0].append(1.0), "support_vectors"),
        (lambda d: d["scaler"].update(kind="robust"), "unknown scaler kind 'robust'"),
        (lambda d: d["lssvr"].update(intercept="zero"), "key 'intercept' has the wrong type"),
        (lambda d: d.update(training=[1, 2]), "key 'training' must be an object"),
        (lambda d: d["lssvr"].update(kernel="poly", degree=-3), "key 'degree' must be a whole number >= 1"),
        (lambda d: d["lssvr"].update(kernel="sigmoid"), "unknown kernel 'sigmoid'"),
        (lambda d: d["scaler"]["scale_"].__setitem__(0, 0.0), "key 'scale_' of the scaler holds a zero"),
    ],
)
def test_bad_model_documents(tmp_path, good_doc, mutate, message):
    mutate(good_doc)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(good_doc))
    with pytest.raises(ModelFileError, match=message):
        load_model(path)


def test_corrupted_and_missing_files(tmp_path, good_doc):
    path = tmp_path / "cut.json"
    path.write_text(json.dumps(good_doc)[:200])
    with pytest.raises(ModelFileError, match=r"cut.json: corrupted JSON at line 1"):
        load_model(path)
    with pytest.raises(ModelFileError, match="cannot read"):
        load_model(tmp_path / "absent.json")
    binary = tmp_path / "model.pkl"
    binary.write_bytes(b"\x80\x04\x95\xff\xfe")
    with pytest.raises(ModelFileError, match="not a text file"):
        load_model(binary)
