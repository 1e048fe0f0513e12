"""`features` says on stderr as each log finishes (run, place in the list, wall time so far), silenced by quiet."""

from __future__ import annotations

from gyrodrift.fleet.features import features_table
from gyrodrift.ins import Scenario, simulate
from gyrodrift.procedure.timeline import Timeline

SHORT = Timeline(align_h=0.1, features_h=1.0, truth_h=1.0, coarse_s=60.0)


def _logs(tmp_path):
    paths = []
    for k in range(2):
        scn = Scenario.from_dict({"run": {"duration_h": 1.2, "rate_hz": 5.0, "seed": k}})
        paths.append(simulate(scn, out_dir=tmp_path / f"run{k}", quiet=True))
    return paths


def test_one_line_per_finished_log_unless_quiet(tmp_path, capsys):
    paths = _logs(tmp_path)
    rows = features_table(paths, timeline=SHORT, quiet=False)
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.startswith("features:")]
    assert [ln.split(" s wall")[0].rsplit(", ", 1)[0] for ln in lines] == [
        "features: run0 done (1/2",
        "features: run1 done (2/2",
    ]
    assert [r.run for r in rows] == ["run0", "run1"]
    features_table(paths, timeline=SHORT, quiet=True)
    assert "features:" not in capsys.readouterr().err
