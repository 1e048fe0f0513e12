"""`gyrodrift export` of the drift law (a hybrid on the fleet-prior smoother): the generated C and Rust build the law
at the end of the 16 h span (`gyrodrift_model_identified_law` / `identified_law`: eps_ref the model's drift, k1 the
smoother's k_z with the fleet's prior, 0 on a constant-model run) and evaluate it at the measured temperature
(`gyrodrift_model_law_deg_h` / `Law::drift_deg_h`), with the same bits as Python's law
(`gyrodrift.procedure.identify.identified_law` evaluated by `gyrodrift.drift_law.DriftLaw.drift_deg_h`) on every row
and temperature, and check the temperature against the training runs' temperatures (`temp_in_range`).

Rows: those of tests/export/test_export_fleet.py (training runs, random rows over 1.2 times the training ranges, a
third on the smoother's constant model, the edges of the thermal test); per row a T_ref and six temperatures (T_ref
itself, a random one 5 degC beyond the training range either side, the range's two ends, the next double above it,
NaN). Tolerance: the same bits (``==``) on every row and temperature. A model without a fleet base exports no law.
"""

from __future__ import annotations

import json
import os
import subprocess

import numpy as np
import pytest
from test_export_fleet import (
    _CARGO_TOML,
    CARGO,
    CC,
    CFLAGS,
    FIELDS,
    KZ,
    _bits,
    _expected,
    _fleet_model,
    _probe_rows,
    _rows_text,
    fleet_runs,
)

from gyrodrift.drift_law import DriftLaw
from gyrodrift.export.languages import export_model
from gyrodrift.export.spec import export_spec
from gyrodrift.learn.drift_model import fit_drift_model
from gyrodrift.learn.fleet_prior import posterior_with_coefficient_prior
from gyrodrift.procedure.identify import fleet_posterior, identified_law
from gyrodrift.procedure.results import RunFeatures
from gyrodrift.runs.table import RunTable

N_TEMPS = 6


def _temperatures(rng: np.random.Generator, n: int, lo: float, hi: float) -> np.ndarray:
    """Per row: T_ref, then `N_TEMPS` temperatures [deg C] (module docstring)."""
    t_ref = rng.uniform(lo, hi, n)
    return np.column_stack(
        [
            t_ref,
            t_ref,
            rng.uniform(lo - 5.0, hi + 5.0, n),
            np.full(n, lo),
            np.full(n, hi),
            np.full(n, np.nextafter(hi, np.inf)),
            np.full(n, np.nan),
        ]
    )


def _k1(model, rows: RunTable) -> np.ndarray:
    """The law's k1 of each row [deg/h/degC]: the fleet posterior's k_z where the row is thermal, else 0."""
    with np.errstate(over="ignore"):  # a k_z 1-sigma squaring to inf (an edge row): not thermal
        thermal, _, k, _, _, _ = posterior_with_coefficient_prior(
            rows.column("drift_smoother_deg_h"),
            rows.column("drift_smoother_std_deg_h"),
            *(rows.column(name) for name in KZ),
            *model.coefficient_prior_,
        )
    return np.where(thermal, k, 0.0)


@pytest.fixture(scope="module")
def law_case():
    """(model, rows, temperatures, expected): the fleet model and rows of test_export_fleet, and Python's law."""
    rng = np.random.default_rng(2026)
    model = _fleet_model(fleet_runs(rng))
    rows = _probe_rows(model.training_["runs"], rng)
    exp = _expected(model, rows)
    train = model.training_["runs"]
    lo, hi = float(train.temp_min_c.min()), float(train.temp_max_c.max())
    temps = _temperatures(np.random.default_rng(21), len(rows), lo, hi)
    k1 = _k1(model, rows)
    laws = [
        DriftLaw(eps_ref_deg_h=float(e), t_ref_c=float(t), k1_deg_h_per_c=float(k))
        for e, t, k in zip(exp["pred"], temps[:, 0], k1, strict=True)
    ]
    values = np.array([law.drift_deg_h(t) for law, t in zip(laws, temps[:, 1:], strict=True)])
    inside = (temps[:, 1:] >= lo) & (temps[:, 1:] <= hi)
    return model, rows, temps, {"k1": k1, "law": values, "temp_inside": inside, "thermal": exp["thermal"]}


def _features(rows: RunTable, i: int, t_end: float) -> RunFeatures:
    return RunFeatures(
        run=str(rows.run[i]),
        lat_deg=float(rows.lat_deg[i]),
        lat0_deg=float(rows.lat0_deg[i]),
        lat_err_curve_arcsec=np.zeros(13),
        temp_start_c=float(rows.temp_min_c[i]),
        temp_end_c=t_end,
        temp_min_c=float(rows.temp_min_c[i]),
        temp_max_c=float(rows.temp_max_c[i]),
        drift_smoother_deg_h=float(rows.column("drift_smoother_deg_h")[i]),
        drift_smoother_std_deg_h=float(rows.column("drift_smoother_std_deg_h")[i]),
        **{name: float(rows.column(name)[i]) for name in KZ},
    )


def test_the_reference_is_the_law_identify_builds(law_case):
    """The vectorised reference here is `identified_law`'s law (what `identify` reports) on the training runs and on
    random rows with and without a thermal k_z, coefficient for coefficient."""
    model, rows, temps, exp = law_case
    from gyrodrift.procedure.features import features_run_table

    n_train = len(model.training_["runs"])
    kz = np.column_stack([rows.column(name) for name in KZ])
    whole = np.isfinite(kz).all(axis=1) | ~np.isfinite(kz).any(axis=1)
    picks = [*range(n_train), *np.flatnonzero(whole[n_train:] & exp["thermal"][n_train:])[:10] + n_train]
    picks += list(np.flatnonzero(whole[n_train:] & ~exp["thermal"][n_train:])[:10] + n_train)
    assert exp["thermal"][picks].any() and not exp["thermal"][picks].all()
    for i in picks:
        f = _features(rows, i, float(temps[i, 0]))
        table = features_run_table([f])
        with np.errstate(over="ignore"):  # a k_z 1-sigma squaring to inf (an edge row): not thermal
            drift = float(model.predict(table)[0])
            law = identified_law(model, table, f, drift, fleet_posterior(f, model.coefficient_prior_))
        assert (law.eps_ref_deg_h, law.t_ref_c, law.k1_deg_h_per_c) == (drift, temps[i, 0], exp["k1"][i]), i
        assert law.drift_deg_h(temps[i, 1:]).tobytes() == exp["law"][i].tobytes()


def test_a_model_without_the_fleet_base_exports_no_law():
    rng = np.random.default_rng(3)
    train = fleet_runs(rng)
    model = fit_drift_model(
        train, encoding="physics", target="residual", physics_column="drift_smoother_deg_h", gamma=100.0, sigma=0.7
    )
    assert export_spec(model).temp_range_c is None
    c, rust = export_model(model, "c"), export_model(model, "rust")["gyrodrift_model.rs"]
    assert "law" not in c["gyrodrift_model.h"] + c["gyrodrift_model.c"] and "Law" not in rust


def test_the_spec_holds_the_training_temperatures(law_case):
    model, _, _, _ = law_case
    train = model.training_["runs"]
    assert export_spec(model).temp_range_c == (train.temp_min_c.min(), train.temp_max_c.max())


_C_DRIVER = """#include <stdio.h>
#include <stdlib.h>
#include "gyrodrift_model.h"

/* Rows of the inputs, T_ref and the temperatures on stdin; per row: k1, then per temperature the law and the check. */
int main(void)
{
    char t[N][64];
    int k;
    while (scanf(FORMAT, TEXTS) == N) {
        gyrodrift_model_inputs in = {VALUES};
        const gyrodrift_model_law law = gyrodrift_model_identified_law(&in, strtod(t[NF], NULL));
        printf("%.17g", law.k1_deg_h_per_c);
        for (k = NF + 1; k < N; ++k) {
            const double temp = strtod(t[k], NULL);
            printf(" %.17g %d", gyrodrift_model_law_deg_h(&law, temp), gyrodrift_model_temp_in_range(temp));
        }
        printf("\\n");
    }
    return 0;
}
"""


def _input_text(rows: RunTable, temps: np.ndarray) -> str:
    lines = _rows_text(rows).splitlines()
    return "".join(f"{line} {' '.join(repr(float(v)) for v in t)}\n" for line, t in zip(lines, temps, strict=True))


def _check(out: str, rows: RunTable, exp: dict, what: str) -> None:
    got = np.array([line.split() for line in out.splitlines()], float)
    assert got.shape == (len(rows), 1 + 2 * N_TEMPS)
    assert _bits(got[:, 0]).tolist() == _bits(exp["k1"]).tolist(), f"{what} k1"
    law, inside = got[:, 1::2], got[:, 2::2].astype(bool)
    same = _bits(law) == _bits(exp["law"])
    assert same.all(), f"{what}: {int((~same).sum())} laws differ, first at row {np.argwhere(~same)[0]}"
    np.testing.assert_array_equal(inside, exp["temp_inside"])
    print(
        f"\n{what}: {len(rows)} rows x {N_TEMPS} temperatures ({int(exp['thermal'].sum())} rows with a thermal k_z): "
        "k1 and the law the same bits as Python's, the temperature check the same"
    )


@pytest.mark.skipif(CC is None, reason="no C compiler (cc) on PATH")
def test_c_gives_the_bits_of_the_law(law_case, tmp_path):
    model, rows, temps, exp = law_case
    for name, text in export_model(model, "c").items():
        (tmp_path / name).write_text(text)
    nf, n = len(FIELDS), len(FIELDS) + 1 + N_TEMPS
    (tmp_path / "driver.c").write_text(
        _C_DRIVER.replace("FORMAT", '"' + " ".join(["%63s"] * n) + '"')
        .replace("TEXTS", ", ".join(f"t[{k}]" for k in range(n)))
        .replace("VALUES", ", ".join(f"strtod(t[{k}], NULL)" for k in range(nf)))
        .replace("char t[N]", f"char t[{n}]")
        .replace("== N)", f"== {n})")
        .replace("k < N;", f"k < {n};")
        .replace("NF", str(nf))
    )
    subprocess.run([CC, *CFLAGS, "driver.c", "gyrodrift_model.c", "-lm", "-o", "driver"], cwd=tmp_path, check=True)
    out = subprocess.run(
        ["./driver"], cwd=tmp_path, input=_input_text(rows, temps), capture_output=True, text=True, check=True
    ).stdout
    _check(out, rows, exp, "C")


_RUST_MAIN = """#[allow(dead_code)] // the functions the check does not call
mod gyrodrift_model;
use gyrodrift_model as m;
use std::io::BufRead;

fn main() {
    let math = m::Math { cos: f64::cos, exp: f64::exp };
    for line in std::io::stdin().lock().lines() {
        let u: Vec<f64> = line.unwrap().split(' ').map(|t| t.parse::<f64>().unwrap()).collect();
        let inputs = m::Inputs { FIELDS };
        let law = m::identified_law(&inputs, &math, u[NF]);
        let mut out = format!("{:e}", law.k1_deg_h_per_c);
        for &temp in &u[NF + 1..] {
            out += &format!(" {:e} {}", law.drift_deg_h(temp), i32::from(m::temp_in_range(temp)));
        }
        println!("{out}");
    }
}
"""


@pytest.mark.skipif(CARGO is None, reason="no cargo on PATH")
def test_rust_gives_the_bits_of_the_law(law_case, tmp_path_factory):
    model, rows, temps, exp = law_case
    project = tmp_path_factory.mktemp("rust_law")
    (project / "src").mkdir()
    (project / "Cargo.toml").write_text(_CARGO_TOML.replace("gyrodrift_fleet_check", "gyrodrift_law_check"))
    (project / "src" / "gyrodrift_model.rs").write_text(export_model(model, "rust")["gyrodrift_model.rs"])
    fields = ", ".join(f"{name}: u[{k}]" for k, name in enumerate(FIELDS))
    (project / "src" / "main.rs").write_text(_RUST_MAIN.replace("FIELDS", fields).replace("NF", str(len(FIELDS))))
    env = {**os.environ, "CARGO_TARGET_DIR": str(tmp_path_factory.getbasetemp() / "cargo-target-law")}
    build = subprocess.run(
        ["cargo", "build", "--offline", "--quiet", "--release"], cwd=project, env=env, capture_output=True, text=True
    )
    assert build.returncode == 0 and "warning" not in build.stderr, build.stderr[-4000:]
    run = subprocess.run(
        ["cargo", "run", "--offline", "--quiet", "--release"],
        cwd=project,
        env=env,
        input=_input_text(rows, temps),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 0, run.stderr[-4000:]
    _check(run.stdout, rows, exp, "Rust")


def test_export_json_says_the_laws_temperature_range(law_case, tmp_path):
    from click.testing import CliRunner

    from gyrodrift.cli import main
    from gyrodrift.learn.model_io import save_model

    model, _, _, _ = law_case
    save_model(model, tmp_path / "m.json")
    r = CliRunner().invoke(
        main, ["export", "--model", str(tmp_path / "m.json"), "--lang", "c", "--out", str(tmp_path / "c"), "--json"]
    )
    assert r.exit_code == 0, r.output
    train = model.training_["runs"]
    assert json.loads(r.stdout)["law_temp_range_c"] == [train.temp_min_c.min(), train.temp_max_c.max()]
