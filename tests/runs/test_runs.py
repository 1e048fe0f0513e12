"""Run tables: the paper's data as embedded, and every malformed CSV with an error naming file, row, column."""

import numpy as np
import pytest

from gyrodrift.learn.baselines import physics_inversion
from gyrodrift.learn.encodings import ENCODINGS, encode, feature_names
from gyrodrift.runs.datasets import load_paper
from gyrodrift.runs.table import RunTableError, parse_temp_range, read_runs_csv


def test_paper_data_has_the_papers_split_and_values():
    d = load_paper()
    assert len(d.train) == 22 and len(d.test) == 10
    assert list(d.test.run) == [str(i) for i in range(23, 33)]
    # Spot values from Table 1 row 8 and Table 2 row 7.
    r8 = d.train.select(d.train.run == "8")
    assert (r8.lat_deg[0], r8.temp_min_c[0], r8.temp_max_c[0], r8.drift_deg_h[0]) == (28.2028, 53.1, 62.3, 0.0033)
    t7 = d.test.select(d.test.run == "29")
    assert (t7.temp_min_c[0], t7.temp_max_c[0], t7.drift_deg_h[0]) == (40.0, 57.5, -0.00345)
    assert np.all(d.runs.lat0_deg == 28.222)
    assert d.feature_names == ("lat_deg", "temp_min_c", "temp_max_c") and d.target_names == ("drift_deg_h",)
    assert "Yu, Zhang, Xie, Long" in d.DESCR
    np.testing.assert_allclose(d.train.lat_err_arcsec[0], (28.2274 - 28.222) * 3600)


def test_encodings_columns():
    d = load_paper()
    for enc in ENCODINGS:
        X = encode(d.train, enc)
        assert X.shape == (22, len(feature_names(enc)))
        first = physics_inversion(d.train) if enc.startswith("physics") else d.train.lat_err_arcsec
        if enc == "temperature":
            first = d.train.temp_min_c
        np.testing.assert_allclose(X[:, 0], first)
    np.testing.assert_allclose(encode(d.train, "physics_lat")[:, 3], d.train.lat0_deg)
    np.testing.assert_allclose(encode(d.train, "temp_span")[:, 1], d.train.temp_max_c - d.train.temp_min_c)
    np.testing.assert_allclose(encode(d.train, "temp_mean")[:, 1], (d.train.temp_max_c + d.train.temp_min_c) / 2)
    with pytest.raises(ValueError, match="unknown encoding 'bogus'"):
        encode(d.train, "bogus")


def _write(tmp_path, text, name="runs.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_range_cells_and_lat0_column(tmp_path):
    p = _write(
        tmp_path,
        "run,lat_deg,lat0_deg,temp_range_c,drift_deg_h\na,28.2274,28.222,37.1~39.5,0.0007\nb,45.0,45.001,10 ~ 12,\n",
    )
    runs = read_runs_csv(p)
    assert list(runs.temp_min_c) == [37.1, 10.0] and list(runs.temp_max_c) == [39.5, 12.0]
    assert np.isnan(runs.drift_deg_h[1]) and not runs.has_truth
    np.testing.assert_allclose(runs.lat_err_arcsec, [(28.2274 - 28.222) * 3600, -0.001 * 3600])
    assert parse_temp_range("37.1\uff5e39.5") == (37.1, 39.5)


@pytest.mark.parametrize(
    "text, kwargs, message",
    [
        ("", {}, r"runs.csv: empty file"),
        ("run,lat_deg,temp_min_c,temp_max_c\n", {"lat0_deg": 28.0}, r"runs.csv: no data rows"),
        (
            "run,lat_deg,temp_min_c,temp_max_c,colour\n1,28,1,2,red\n",
            {"lat0_deg": 28.0},
            r"row 1: unknown column 'colour'",
        ),
        (
            "run,temp_min_c,temp_max_c\n1,1,2\n",
            {"lat0_deg": 28.0},
            r"row 1: missing column 'lat_deg' \(latitude at the 12th hour of free navigation, deg\)$",
        ),
        (
            "run,lat_deg\n1,28\n",
            {"lat0_deg": 28.0},
            r"row 1: missing columns: expected temp_min_c and temp_max_c, or temp_range_c",
        ),
        (
            "run,lat_deg,temp_min_c,temp_max_c\n1,28,1,2\n",
            {},
            r"no lat0_deg column; give the true site latitude \(--lat0-deg, or lat0_deg= in Python\)$",
        ),
        (
            "run,lat_deg,temp_min_c,temp_max_c\n1,28,1,2\n",
            {"lat0_deg": 28.0, "require_truth": True},
            r"missing column 'drift_deg_h' \(true axial drift, the training label, deg/h\) for training$",
        ),
        (
            "run,lat_deg,temp_min_c,temp_max_c\n1,28,1,2\n2,abc,1,2\n",
            {"lat0_deg": 28.0},
            r"runs.csv, row 3, column lat_deg: expected a latitude in degrees, got 'abc'",
        ),
        (
            "run,lat_deg,temp_min_c,temp_max_c\n1,128,1,2\n",
            {"lat0_deg": 28.0},
            r"row 2, column lat_deg: expected a latitude within \[-90, 90\]",
        ),
        (
            "run,lat_deg,temp_min_c,temp_max_c\n1,28,nan,2\n",
            {"lat0_deg": 28.0},
            r"row 2, column temp_min_c: expected a finite number",
        ),
        (
            "run,lat_deg,temp_min_c,temp_max_c\n1,28,5,2\n",
            {"lat0_deg": 28.0},
            r"row 2, column temp_max_c: maximum temperature 2.0 is below the minimum 5.0",
        ),
        (
            "run,lat_deg,temp_range_c\n1,28,37.1-39.5\n",
            {"lat0_deg": 28.0},
            r"row 2, column temp_range_c: expected a range like 37.1~39.5, got '37.1-39.5'",
        ),
        ("run,lat_deg,temp_min_c,temp_max_c\n1,28,1\n", {"lat0_deg": 28.0}, r"row 2: expected 4 cells, got 3"),
        (
            "run,lat_deg,temp_min_c,temp_max_c,drift_deg_h\n1,28,1,2,\n",
            {"lat0_deg": 28.0, "require_truth": True},
            r"row 2, column drift_deg_h: expected a drift in deg/h for training",
        ),
        (
            "run,lat_deg,temp_min_c,temp_max_c,drift_deg_h\n1,28,1,2,36\n",
            {"lat0_deg": 28.0},
            r"row 2, column drift_deg_h: \|36.0\| deg/h is not an RLG drift",
        ),
        (
            "run,lat_deg,temp_min_c,temp_max_c\n1,28,1,2\n1,28,1,2\n",
            {"lat0_deg": 28.0},
            r"row 3, column run: run '1' appears more than once \(first in row 2",
        ),
        (
            "run,lat_deg,temp_min_c,temp_max_c\n1,28,1,2\n",
            {"lat0_deg": 1000.0},
            r"runs.csv: site latitude lat0_deg must be within \[-90, 90\] deg, got 1000.0",
        ),
        (
            "run,lat_deg,temp_min_c,temp_max_c\n1,28,1,2\n",
            {"lat0_deg": float("nan")},
            r"site latitude lat0_deg must be within",
        ),
        (
            "run,lat_deg,lat_deg,temp_min_c,temp_max_c\n1,28,28,1,2\n",
            {"lat0_deg": 28.0},
            r"column 'lat_deg' appears twice",
        ),
        (
            "run,split,lat_deg,temp_min_c,temp_max_c\n1,validate,28,1,2\n",
            {"lat0_deg": 28.0},
            r"column split: expected 'train' or 'test'",
        ),
    ],
)
def test_bad_tables_name_file_row_and_column(tmp_path, text, kwargs, message):
    p = _write(tmp_path, text)
    with pytest.raises(RunTableError, match=message):
        read_runs_csv(p, **kwargs)


def test_binary_file(tmp_path):
    p = tmp_path / "bin.csv"
    p.write_bytes(b"run,lat_deg,temp_min_c,temp_max_c\n1,28,1,2\n\xff\xfe\x00\x81\n")
    with pytest.raises(RunTableError, match=r"bin.csv, row 3: not UTF-8 text"):
        read_runs_csv(p, lat0_deg=28.0)


def test_missing_file(tmp_path):
    with pytest.raises(RunTableError, match=r"nope.csv: cannot open"):
        read_runs_csv(tmp_path / "nope.csv", lat0_deg=0.0)


# --- records, structured arrays and indexing (how a model file and scikit-learn see a table) ------------------
def test_records_and_structured_arrays_round_trip_with_the_csv_checks():
    from gyrodrift.runs.table import RunTable, as_run_table

    runs = load_paper().runs
    again = RunTable.from_records(runs.records(), source="x")
    structured = as_run_table(runs.to_structured())
    for table in (again, structured):
        for name in ("run", "lat_deg", "lat0_deg", "temp_min_c", "temp_max_c", "drift_deg_h", "split"):
            assert np.array_equal(getattr(table, name), getattr(runs, name)), name
    bad = runs.records()
    bad[4]["temp_max_c"] = 303.0
    with pytest.raises(RunTableError, match=r"x, run 5, key temp_max_c: temperature 303.0 outside \[-100, 200\]"):
        RunTable.from_records(bad, source="x")
    bad = runs.records()
    bad[2]["run"] = bad[0]["run"]
    with pytest.raises(RunTableError, match=r"x, run 3: run '1' appears more than once"):
        RunTable.from_records(bad, source="x")
    with pytest.raises(RunTableError, match="expected a RunTable or a 1-D structured array"):
        as_run_table([[1.0, 2.0]])


def test_a_table_indexes_like_a_one_dimensional_array():
    runs = load_paper().runs
    assert runs.shape == (32,)
    assert list(runs[[0, 3]].run) == ["1", "4"] and list(runs[np.arange(2), ...].run) == ["1", "2"]
    assert list(runs[runs.split == "test"].run) == list(runs.select(runs.split == "test").run)
    assert len(runs[5]) == 1 and len(runs[2:4]) == 2


def test_malformed_csv_is_a_run_table_error_with_its_row(tmp_path):
    path = tmp_path / "big.csv"
    path.write_text('run,lat_deg,temp_min_c,temp_max_c\n1,28.2,1,2\n2,"' + "x" * 200_000 + '",1,2\n')
    with pytest.raises(RunTableError, match=r"big.csv, row 3: malformed CSV"):
        read_runs_csv(path, lat0_deg=28.222)


def test_thermal_columns_name_their_own_unit(tmp_path):
    """The smoother's k_z columns are in deg/h/degC (the cov in (deg/h)^2/degC), not deg/h; their 1-sigma > 0."""
    header = "run,lat_deg,lat0_deg,temp_min_c,temp_max_c,smoother_coeff_deg_h_per_c,smoother_coeff_std_deg_h_per_c"
    for cells, message in (
        ("abc,2e-4", "column smoother_coeff_deg_h_per_c: expected a number in deg/h/degC, got 'abc'"),
        ("2e-4,-1e-4", "column smoother_coeff_std_deg_h_per_c: expected a 1-sigma > 0 deg/h/degC"),
        ("20,1e-4", "|20.0| deg/h/degC is not an RLG value"),
    ):
        path = tmp_path / "runs.csv"
        path.write_text(f"{header}\nr1,40.001,40,30,35,{cells}\n")
        with pytest.raises(RunTableError) as info:
            read_runs_csv(path)
        assert message in str(info.value) and "row 2" in str(info.value)
    path.write_text(f"{header}\nr1,40.001,40,30,35,2e-4,1e-4\nr2,40.001,40,30,35,,\n")
    coeff = read_runs_csv(path).column("smoother_coeff_deg_h_per_c")
    assert coeff[0] == 2e-4 and np.isnan(coeff[1])
