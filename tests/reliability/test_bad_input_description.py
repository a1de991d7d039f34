"""Bad descriptions past the preprocessor: nesting, numbers, array sizes; a located error, nothing written."""
from __future__ import annotations

import pytest

from badinputkit import genom2bip

pytestmark = pytest.mark.reliability


def _refused(tmp_path, name: str, text: str, expected: str):
    """Generate from ``text``: exit 1, ``expected`` first on stderr, no output directory, never an internal error."""
    gen = tmp_path / name
    gen.write_text(text)
    done = genom2bip(gen, "-o", tmp_path / "out")
    assert done.code == 1, done.err
    assert done.err.startswith(f"{gen}:{expected}\n"), done.err
    assert "internal error" not in done.err and "Traceback" not in done.err
    assert not (tmp_path / "out").exists()
    return done


def test_structs_nested_3000_deep_are_refused_where_the_nesting_passes_the_limit(tmp_path):
    n = 3000
    text = "component c {\n  ids {\n" + "struct s { " * n + "long x; " + "} a; " * n + "\n  };\n};\n"
    done = _refused(tmp_path, "deep.gen", text,
                    "3:1079: error: nested too deeply: more than 200 levels of declarations and expressions")
    assert "hint: a struct inside a struct takes two levels, an operator one" in done.err
    assert max(len(line) for line in done.err.splitlines()) < 220  # the 40 kB line is quoted around the column


def test_structs_nested_95_deep_are_read(tmp_path):
    gen = tmp_path / "deep.gen"
    gen.write_text("component c {\n  ids {\n" + "struct s { " * 95 + "long x; " + "} a; " * 95 + "\n  };\n};\n")
    done = genom2bip("check", gen)
    assert done.code == 0, done.err


def test_an_expression_of_3000_operators_is_refused(tmp_path):
    _refused(tmp_path, "chain.gen", "const long k =\n  " + " + ".join(["1"] * 3000) + ";\ncomponent c;\n",
             "2:3: error: nested too deeply: more than 200 levels of declarations and expressions")


def test_genom2_structs_nested_3000_deep_are_refused(tmp_path):
    n = 3000
    text = ("typedef struct S {\n" + "struct { " * n + "int x; " + "} a; " * n + "} S;\n"
            "module m { number: 1; internal_data: S; };\n")
    _refused(tmp_path, "deep2.gen", text,
             "2:586: error: nested too deeply: more than 200 levels of declarations and expressions")


def test_an_integer_of_5000_digits_is_out_of_range_not_an_internal_error(tmp_path):
    _refused(tmp_path, "big.gen", "component c;\nconst long x = " + "9" * 5000 + ";\n",
             "2:16: error: 99999999999999999999... is out of range: an integer has 64 bits at most "
             "(from -2**63 to 2**64 - 1)")


def test_a_genom2_integer_of_5000_digits_is_out_of_range(tmp_path):
    _refused(tmp_path, "big2.gen", "#define K " + "9" * 5000 + "\ntypedef struct S { int a[K]; } S;\n"
             "module m { number: 1; internal_data: S; };\n",
             "2:26: error: 99999999999999999999... is out of range: an integer has 64 bits at most "
             "(from -2**63 to 2**64 - 1)")


def test_an_infinite_default_is_refused_not_written_as_inf(tmp_path):
    _refused(tmp_path, "inf.gen", "component c {\n  ids { double d; };\n  attribute A(in d = 1e400);\n};\n",
             "3:22: error: 1e400 is out of range: a floating-point number is at most 1.8e308 in magnitude")


def test_an_integer_constant_outside_its_type_is_refused(tmp_path):
    _refused(tmp_path, "short.gen", "component c;\nconst short s = 100000;\n",
             "2:17: error: constant 's' has type short: 100000 is out of its range, -32768 to 32767")


def test_a_shift_by_a_hundred_billion_is_refused_at_once(tmp_path):
    done = _refused(tmp_path, "shift.gen", "component c;\nconst long long k = 1 << 100000000000;\n",
                    "2:21: error: shift count 100000000000 is out of range: an integer has 64 bits at most")
    assert done.peak_mb < 300


@pytest.mark.parametrize("period, expected", [
    ("1e-300 s", "3:19: error: period must be between 1 us and 1 day, not 1e-300 s"),
    ("1e300 s", "3:19: error: period must be between 1 us and 1 day, not 1e300 s"),
    ("1e400 ms", "3:19: error: 1e400 is out of range: a floating-point number is at most 1.8e308 in magnitude"),
])
def test_a_period_out_of_range_is_refused(tmp_path, period, expected):
    _refused(tmp_path, "period.gen", f"component c {{\n  ids {{ long n; }};\n  task t {{ period {period}; }};\n}};\n",
             expected)


def test_an_array_of_a_hundred_million_numbers_is_refused_before_memory_runs_out(tmp_path):
    done = _refused(tmp_path, "array.gen", "component c {\n  ids { long a[100000000]; };\n};\n",
                    "2:14: error: ids member 'a' would hold 100,000,000 numbers: more than the 4,194,304 one value "
                    "may hold")
    assert "hint: a sequence<T, N> holds only what is written into it" in done.err
    assert done.peak_mb < 300
