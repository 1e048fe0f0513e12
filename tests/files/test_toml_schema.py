"""The TOML validation toolkit: each spec's refusals are one line naming the file, table and key."""

import math

import pytest

from gyrodrift.files.toml_schema import Choice, Flag, Integer, Number, Numbers, Scope, fmt_number, show


class SpecError(ValueError):
    pass


ROOT = Scope("f.toml", SpecError)
SEC = ROOT.section("s")


def message(spec, value) -> str:
    with pytest.raises(SpecError) as info:
        spec.read(SEC, "k", value)
    return str(info.value)


@pytest.mark.parametrize(
    ("spec", "value", "expected"),
    [
        (Number(), "1", "expected a number, got string '1'"),
        (Number(), True, "expected a number, got boolean True"),
        (Number(), math.nan, "expected a finite number, got nan"),
        (Number(), 10**400, "expected a finite number, got an integer of about 401 digits"),
        (Number.positive(), 0, "must be > 0, got 0"),
        (Number.positive(at_most=2.5, unit=" h"), 3, "must be at most 2.5 h, got 3"),
        (Number.non_negative(), -0.5, "must be >= 0, got -0.5"),
        (Number.in_range(-89.0, 89.0), 90, "must be between -89 and 89, got 90"),
        (Number.in_range(-90.0, 90.0, strictly=True), -90, "must be strictly between -90 and 90, got -90"),
        (Integer(ge=0), 1.5, "expected an integer, got number 1.5"),
        (Integer(ge=0), -3, "must be >= 0, got -3"),
        (Integer(lt=2**64, lt_text="2**64"), 2**64, "must be < 2**64, got 18446744073709551616"),
        (Numbers(3), [1, 2], "expected 3 numbers, got 2"),
        (Numbers(3), 0.5, "expected 3 numbers, got number 0.5"),
        (Numbers(), [], "expected at least 1 number, got 0"),
        (Numbers(), "a", "expected an array of numbers, got string 'a'"),
        (Numbers(2), [0, "a"], "element 1: expected a number, got string 'a'"),
        (Numbers(2), [0, math.inf], "element 1: expected a finite number, got inf"),
        (Choice(("a", "b")), "c", "expected one of 'a', 'b', got 'c'"),
        (Choice(("a", "b")), ["a"], "expected one of 'a', 'b', got ['a']"),
        (Flag(), 1, "expected true or false, got number 1"),
    ],
)
def test_each_spec_refuses_with_the_file_table_and_key(spec, value, expected):
    assert message(spec, value) == f"f.toml: [s] k: {expected}"


def test_accepted_values_and_defaults_are_converted():
    assert Number.in_range(0.0, 1.0).read(SEC, "k", 1) == 1.0 and isinstance(Number().read(SEC, "k", 1), float)
    assert Numbers(2).read(SEC, "k", [1, 2.5]) == (1.0, 2.5)
    assert Integer(ge=0).read(SEC, "k", 7) == 7
    assert Choice(("a", "b")).read(SEC, "k", "b") == "b"


def test_tables_fields_and_nested_scopes_name_the_place():
    specs = {"x": Number.positive(), "v": Numbers(2)}

    class Defaults:
        x, v = 2, (1, 2)

    data = {"s": {"x": 3}}
    t = ROOT.table(data, "s", allowed=specs)
    assert SEC.fields(t, specs, Defaults()) == {"x": 3.0, "v": (1.0, 2.0)}
    assert SEC.fields({}, specs) == {"x": None, "v": None}
    assert ROOT.table({}, "s", allowed=specs) == {}
    with pytest.raises(SpecError, match=r"^f.toml: \[s\] must be a table, got number$"):
        ROOT.table({"s": 3}, "s", allowed=specs)
    with pytest.raises(SpecError, match=r"^f.toml: \[s\] y: unknown key \(expected one of: x, v\)$"):
        ROOT.table({"s": {"y": 1}}, "s", allowed=specs)
    rows = SEC.tables("rows", [{"x": 1}, 5])
    scope, row = next(rows)
    assert row == {"x": 1}
    with pytest.raises(SpecError, match=r"^f.toml: \[s\] rows\[0\].x: must be > 0, got -1$"):
        scope.fields({"x": -1}, specs)
    with pytest.raises(SpecError, match=r"^f.toml: \[s\] rows\[0\]: missing v$"):
        scope.require(row, ("x", "v"))
    with pytest.raises(SpecError, match=r"^f.toml: \[s\] rows\[0\]: give exactly one of x and v$"):
        scope.one_of({"x": 1, "v": 2}, "x", "v")
    with pytest.raises(SpecError, match=r"^f.toml: \[s\] rows\[1\]: expected a table, got number 5$"):
        next(rows)
    with pytest.raises(SpecError, match=r"^f.toml: \[s\] rows: expected a non-empty array of tables, got array \[\]$"):
        SEC.tables("rows", [], non_empty=True)
    with pytest.raises(SpecError, match=r"^f.toml: top$"):
        raise ROOT.fail(None, "top")


def test_messages_print_numbers_short():
    assert (fmt_number(90.0), fmt_number(0.5), fmt_number(1e300)) == ("90", "0.5", "1e+300")
    assert show("x" * 100).endswith("...") and len(show("x" * 100)) == 60
