"""Issue 22: fit's summary (text and --json) names the encoding the model file records, never ``None``."""

import json

from click.testing import CliRunner

from gyrodrift.cli import main
from gyrodrift.runs.datasets import paper_csv_path


def test_fit_names_the_encoding_of_its_model_file(tmp_path):
    data = tmp_path / "paper.csv"
    data.write_bytes(paper_csv_path().read_bytes())
    common = [str(data), "--split", "train", "--lat0-deg", "28.222", "--method", "grid"]
    text_model, json_model = tmp_path / "text.json", tmp_path / "json.json"
    text = CliRunner().invoke(main, ["fit", *common, "--out", str(text_model)])
    assert text.exit_code == 0, text.output
    as_json = CliRunner().invoke(main, ["fit", *common, "--out", str(json_model), "--json"])
    assert as_json.exit_code == 0, as_json.output
    recorded = json.loads(text_model.read_text())["encoding"]
    assert isinstance(recorded, str) and recorded == json.loads(json_model.read_text())["encoding"]
    assert f"(fitted on 22 runs, {recorded}, target" in text.stdout and "None" not in text.stdout
    assert json.loads(as_json.stdout)["encoding"] == recorded
