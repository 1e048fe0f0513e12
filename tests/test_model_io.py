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
    assert doc["schema_version"] == 2 and doc["encoding"] == encoding
    assert doc["training"]["sha256"] == training_digest(paper.train)
    assert len(doc["training"]["runs"]) == 22


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
        (lambda d: d.pop("lssvr_params"), "missing key 'lssvr_params'"),
        (lambda d: d.update(encoding="weird"), "unknown encoding 'weird'"),
        (lambda d: d["training"]["runs"][0].pop("lat_deg"), "run 1: missing key 'lat_deg'"),
        (lambda d: d["lssvr_params"].update(sigma=-1.0), "sigma"),
        (lambda d: d["training"]["runs"][0].update(extra=1.0), "unknown key 'extra'"),
        (lambda d: d.update(scaling="robust"), "unknown scaling 'robust'"),
        (lambda d: d["training"]["runs"][0].update(lat_deg="zero"), "key lat_deg: expected a number"),
        (lambda d: d.update(training=[1, 2]), "key 'training' has the wrong type"),
        (lambda d: d["lssvr_params"].update(method="annealing"), "unknown method 'annealing'"),
        (lambda d: d["lssvr_params"].update(objective="sigmoid"), "unknown objective 'sigmoid'"),
        (lambda d: d["training"].update(sha256="0" * 64), "do not match their sha256"),
        (lambda d: d["fitted"].update(intercept_deg_h=1.0), "key 'intercept_deg_h' differs"),
        (lambda d: d["training"]["runs"][3].update(drift_deg_h=11.0), "run 4, key drift_deg_h"),
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
