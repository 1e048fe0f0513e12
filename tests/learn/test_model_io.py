"""Model files: exact round trip, and clear errors for anything that is not a valid model file."""

import json
import re
from pathlib import Path

import numpy as np
import pytest

from gyrodrift.learn.drift_model import fit_drift_model
from gyrodrift.learn.model_io import ModelFileError, load_model, load_predictor, model_to_dict, save_model
from gyrodrift.learn.training_record import training_digest
from gyrodrift.runs.datasets import load_paper


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
    assert doc["schema_version"] == 4 and doc["encoding"] == encoding
    assert doc["training"]["sha256"] == training_digest(paper.train)
    assert len(doc["training"]["runs"]) == 22


def test_tuned_model_keeps_its_tuning_record(tmp_path, paper):
    model = fit_drift_model(paper.train, method="grid", rng=0)
    save_model(model, tmp_path / "m.json")
    again = load_model(tmp_path / "m.json")
    assert again.tuning.method == "grid" and again.tuning.gamma == model.lssvr.gamma


def test_load_takes_the_stored_solution_without_solving_and_older_files_are_solved_again(
    tmp_path, paper, good_doc, monkeypatch
):
    from gyrodrift.learn.lssvr import LSSVR
    from gyrodrift.learn.model_io import model_from_dict

    model = fit_drift_model(paper.train, gamma=10.0, sigma=1.0)
    assert good_doc["fitted"]["dual_coef_deg_h"] == model.lssvr.alpha_.tolist()
    older = json.loads(json.dumps(good_doc))
    del older["fitted"]["dual_coef_deg_h"]
    again = model_from_dict(older)  # before the stored solution: the LSSVR is solved again
    np.testing.assert_array_equal(again.predict(paper.test), model.predict(paper.test))
    older["fitted"]["intercept_deg_h"] += 1e-3
    with pytest.raises(ModelFileError, match="key 'intercept_deg_h' differs"):
        model_from_dict(older)

    def no_solve(self, *args, **kwargs):
        raise AssertionError("the load solved the LSSVM system")

    monkeypatch.setattr(LSSVR, "fit", no_solve)
    loaded = model_from_dict(json.loads(json.dumps(good_doc)))
    np.testing.assert_array_equal(loaded.predict(paper.test), model.predict(paper.test))
    np.testing.assert_array_equal(loaded.loo_residuals(), model.loo_residuals())
    assert good_doc["fitted"]["interval_disagreement_deg_h"] == model.interval_.disagreement_deg_h_
    assert not hasattr(loaded.interval_.spread_, "L_")  # the GP's n x n factor waits for the first interval
    for got, want in zip(loaded.predict_interval(paper.test), model.predict_interval(paper.test), strict=True):
        np.testing.assert_array_equal(got, want)
    np.testing.assert_array_equal(loaded.interval_.spread_.L_, model.interval_.spread_.L_)


def test_digest_changes_with_the_data(paper):
    assert training_digest(paper.train) != training_digest(paper.test)
    assert training_digest(paper.train) == training_digest(load_paper().train)


def test_a_training_column_without_a_known_value_round_trips(tmp_path, paper):
    # a run table can carry an optional column every run leaves unknown (e.g. the truth's best law's k1 1-sigma when
    # no run has a temperature change); the model file leaves unknown values out, so the column must not enter the
    # digest either, or the file's own runs would not match it on load
    train = paper.train
    unknown = train.replace(extra={**train.extra, "truth_law_k1_std_deg_h_per_c": np.full(len(train), np.nan)})
    assert training_digest(unknown) == training_digest(train)
    model = fit_drift_model(unknown, gamma=50.0, sigma=1.3)
    save_model(model, tmp_path / "m.json")
    np.testing.assert_array_equal(load_model(tmp_path / "m.json").predict(paper.test), model.predict(paper.test))


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
        (lambda d: d["fitted"].update(intercept_deg_h=1.0), "stored solution does not solve the LSSVM system"),
        (lambda d: d["fitted"]["dual_coef_deg_h"].__setitem__(0, 1.0), "stored dual coefficients do not sum to 0"),
        (lambda d: d["fitted"].update(dual_coef_deg_h=[0.0]), "key 'dual_coef_deg_h' must be a list of 22"),
        (lambda d: d["training"]["runs"][3].update(drift_deg_h=11.0), "run 4, key drift_deg_h"),
    ],
)
@pytest.mark.parametrize("load", [load_model, load_predictor])
def test_bad_model_documents(tmp_path, good_doc, mutate, message, load):
    mutate(good_doc)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(good_doc))
    with pytest.raises(ModelFileError, match=message):
        load(path)


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


# --- issue 8: hostile model files, old files, what fit warns about ------------------------------------------
def test_schema_1_file_written_before_the_pipeline_model_is_refused_with_a_refit_message():
    # tests/data/model_schema1.json was written by gyrodrift at commit a88f125 (fit_drift_model on the paper's
    # training runs, temp_mean, minmax, gamma 30, sigma 1.5): fitted internals, no training runs.
    path = Path(__file__).parents[1] / "data" / "model_schema1.json"
    assert json.loads(path.read_text())["schema_version"] == 1
    with pytest.raises(
        ModelFileError, match=r"model_schema1.json: a schema 1 model file .* refit it with `gyrodrift fit`"
    ):
        load_model(path)


@pytest.mark.parametrize(
    "edit, key",
    [
        (lambda t: t.replace('"gamma": 10.0', '"gamma": ' + "7" * 450), "gamma"),
        (lambda t: t.replace('"gamma": 10.0', '"gamma": ' + "7" * 5000), "gamma"),
        (lambda t: t.replace('"lat_deg": 28.2', '"lat_deg": -' + "9" * 401 + '.0, "x": 28.2', 1), None),
        (lambda t: t.replace('"n_particles": 30', '"n_particles": ' + "3" * 420), "n_particles"),
    ],
)
def test_huge_integers_name_file_and_key(tmp_path, good_doc, edit, key):
    text = edit(json.dumps(good_doc))
    path = tmp_path / "huge.json"
    path.write_text(text)
    with pytest.raises(ModelFileError, match=r"huge.json") as info:
        load_model(path)
    if key is not None:
        assert re.search(rf"key '[\w.]*{key}' holds an integer of \d+ digits", str(info.value)), info.value


def test_huge_integer_that_python_reads_but_float_cannot_names_the_key(tmp_path, good_doc):
    good_doc["lssvr_params"]["gamma"] = 10**350  # 351 digits: below the digit guard, above float range
    good_doc["lssvr_params"]["sigma"] = 1.0
    path = tmp_path / "big.json"
    path.write_text(json.dumps(good_doc))
    with pytest.raises(ModelFileError, match=r"big.json \[lssvr_params\]: key 'gamma' holds an integer too large"):
        load_model(path)


def test_deeply_nested_json_is_a_model_file_error(tmp_path):
    path = tmp_path / "deep.json"
    path.write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(ModelFileError, match="deep.json: JSON nested too deeply"):
        load_model(path)
    path.write_text(
        '{"format": "gyrodrift-drift-model", "schema_version": 2, "encoding": ' + "[" * 500 + "]" * 500 + "}"
    )
    with pytest.raises(ModelFileError, match="deep.json: key 'encoding' has the wrong type"):
        load_model(path)


@pytest.mark.parametrize("sigma", [1e-200, 1e200])
def test_a_model_file_with_a_sigma_whose_square_is_not_a_normal_float_is_refused(tmp_path, good_doc, sigma):
    good_doc["lssvr_params"]["sigma"] = sigma
    path = tmp_path / "tiny.json"
    path.write_text(json.dumps(good_doc))
    with pytest.raises(ModelFileError, match=r"tiny.json: the model cannot be rebuilt .* sigma must be within"):
        load_model(path)


def test_an_ill_conditioned_model_file_is_refused(tmp_path, good_doc):
    good_doc["lssvr_params"].update(gamma=1e16, sigma=100.0)
    good_doc["fitted"].update(gamma=1e16, sigma=100.0)
    path = tmp_path / "ill.json"
    path.write_text(json.dumps(good_doc))
    with pytest.raises(ModelFileError, match=r"ill.json: .*stored solution does not solve the LSSVM system"):
        load_model(path)  # the stored solution is for gamma 10, sigma 1
    del good_doc["fitted"]["dual_coef_deg_h"]  # a file from before the stored solution: solved again
    path.write_text(json.dumps(good_doc))
    # cond 2.7e18 on one BLAS, a failed Cholesky factorisation on an AMD EPYC's OpenBLAS: one refusal either way
    with pytest.raises(ModelFileError, match=r"ill.json: .*gamma=1e\+16, sigma=100\.0, kernel='rbf' cannot be solved"):
        load_model(path)


def test_fit_warns_on_the_search_box_edge_on_stderr_and_in_the_file(tmp_path, paper):
    from click.testing import CliRunner

    from gyrodrift.cli import main
    from gyrodrift.runs.datasets import paper_csv_path

    csv_path = tmp_path / "paper.csv"
    csv_path.write_bytes(paper_csv_path().read_bytes())
    out = tmp_path / "m.json"
    args = ["fit", str(csv_path), "--lat0-deg", "28.222", "--split", "train", "--out", str(out), "--quiet"]
    r = CliRunner().invoke(main, args + ["--objective", "train_mae", "--method", "grid"])
    assert r.exit_code == 0, r.output
    assert "warning: tuned value on the edge of its search box: gamma = 100000 in [0.01, 100000]" in r.stderr
    doc = json.loads(out.read_text())
    assert doc["fitted"]["on_search_bound"] == ["gamma"] and doc["warnings"][0].startswith("tuned value on the edge")
    r = CliRunner().invoke(main, args + ["--method", "grid"])  # the LOO optimum lies inside the box
    assert r.exit_code == 0 and "edge of its search box" not in r.stderr  # the interval may warn of its own
    assert not [w for w in json.loads(out.read_text())["warnings"] if "edge of its search box" in w]


@pytest.mark.parametrize(
    "extra, exit_code, message",
    [
        (["--gamma", "1", "--sigma", "1e-200"], 2, "Invalid value for '--sigma'"),
        (["--gamma", "nan", "--sigma", "1"], 2, "Invalid value for '--gamma'"),
        # the condition-number refusal or a failed Cholesky factorisation (which one depends on the BLAS): one message
        (["--split", "train", "--gamma", "1e16", "--sigma", "100"], 1, "--gamma 1e+16 --sigma 100: LSSVR: H = K"),
        (["--gamma", "1e16", "--sigma", "100"], 1, "--gamma 1e+16 --sigma 100: LSSVR: H = K + I/gamma for gamma=1e+16"),
    ],
)
def test_fit_refuses_fixed_parameters_with_no_meaningful_solution(tmp_path, extra, exit_code, message):
    from click.testing import CliRunner

    from gyrodrift.cli import main
    from gyrodrift.runs.datasets import paper_csv_path

    csv_path = tmp_path / "paper.csv"
    csv_path.write_bytes(paper_csv_path().read_bytes())
    out = tmp_path / "m.json"
    r = CliRunner().invoke(main, ["fit", str(csv_path), "--lat0-deg", "28.222", "--out", str(out), *extra])
    assert r.exit_code == exit_code and message in r.output, r.output
    assert exit_code == 2 or "kernel='rbf' cannot be solved: " in r.output
    assert "Traceback" not in r.output and not out.exists()


def test_ill_conditioned_but_usable_fit_warns_with_the_condition_number(tmp_path):
    from click.testing import CliRunner

    from gyrodrift.cli import main
    from gyrodrift.runs.datasets import paper_csv_path

    csv_path = tmp_path / "paper.csv"
    csv_path.write_bytes(paper_csv_path().read_bytes())
    out = tmp_path / "m.json"
    args = ["fit", str(csv_path), "--lat0-deg", "28.222", "--split", "train", "--out", str(out)]
    # cond 1.23e14 on an AMD EPYC (gamma 1e14 gave 3.2e15 here and 4.83e15, over 1/eps, there): well inside
    # the warning band (4.5e12, 4.5e15) on any BLAS
    r = CliRunner().invoke(main, args + ["--gamma", "3e12", "--sigma", "100"])
    assert r.exit_code == 0, r.output
    assert re.search(r"warning: LSSVR: H = K \+ I/gamma .* condition number \d\.\d+e\+1[34] > 4\.5e\+12", r.stderr)
    assert "condition number" in json.loads(out.read_text())["warnings"][0]
