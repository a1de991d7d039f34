"""Timed BIP2 text: clocks, urgency, resume, invariants and rates are read, checked (where they are) and written."""
from pathlib import Path

import pytest

from genom2bip.back.bip2 import BipWriteError, write_package
from runtime.bip2 import parse_file, parse_text
from runtime.diagnostics import DiagnosticError
from runtime.model import Const, Var
from runtime.model.timing import Rate

TIMED = Path(__file__).parent / "fixtures" / "bip" / "timed"
FIXTURES = sorted(TIMED.glob("*.bip"))


@pytest.mark.parametrize("path", FIXTURES, ids=lambda p: p.stem)
def test_timed_fixtures_read_back_equal(path):
    package = parse_file(path)
    text = write_package(package)
    again = parse_text(text, path.name)
    assert again == package
    assert write_package(again) == text


def test_what_is_read():
    pkg = parse_file(TIMED / "resumer.bip")
    worker = pkg.atom_types[0]
    assert [(c.name, c.unit, c.nanoseconds) for c in worker.clocks] == [("x", "second", 10**9),
                                                                        ("slow", "second", 10**9)]
    start, hand = worker.transitions
    assert (start.urgency, hand.urgency) == ("eager", "lazy")
    assert start.resume.guard is not None and hand.resume is None
    assert worker.initial.resume is not None and worker.initial.resume.guard is None
    assert Rate("slow", Const(0.5)) in worker.initial.action
    (busy,) = worker.invariants
    assert (busy.name, busy.places) == ("busy", ["BUSY"])


def test_default_unit_is_the_second():
    pkg = parse_text(ATOM.format(clock="clock c", guard="c >= 2", extra=""), "p.bip")
    (c,) = pkg.atom_types[0].clocks
    assert c.unit is None and c.nanoseconds == 10**9
    assert "    clock c\n" in write_package(pkg)


ATOM = """package P
  port type Port()
  atom type A()
    data int n = 0
    {clock}
    port Port p(), q()
    place S, T
    initial to S do {{ c = 0; }}
    on p from S to T provided ({guard}) eager
    {extra}
  end
  compound type K()
    component A a()
  end
end
"""


def located(text: str, message: str, needle: str, nth: int = 1):
    with pytest.raises(DiagnosticError) as err:
        parse_text(text, "bad.bip")
    diags = err.value.diagnostics
    assert len(diags) == 1, [d.render() for d in diags]
    d = diags[0]
    pos = -1
    for _ in range(nth):
        pos = text.index(needle, pos + 1)
    line = text.count("\n", 0, pos) + 1
    column = pos - (text.rfind("\n", 0, pos) + 1) + 1
    assert message in d.message, d.render()
    assert (d.span.file, d.span.line, d.span.column) == ("bad.bip", line, column), d.render()


@pytest.mark.parametrize("guard, extra, message, needle, nth", [
    ("c != 3", "", "operator '!=' applied to expressions involving clocks", "c != 3", 1),
    ("!(c < 3)", "", "operator '!' applied to an expression involving clocks", "c < 3", 1),
    ("c < 1 || c > 3", "", "clocks found on both sides of '||'", "c < 1", 1),
    ("(c < 3) == true", "", "nested comparison applied to an expression involving clocks", "c < 3", 1),
    ("c * c < 3", "", "operator '*' makes the constraint non-linear", "c * c", 1),
    ("c", "", "clock 'c' used as a condition", "c)", 1),
    ("c >= 1", "internal from T to S provided (c > 2)", "an internal transition's guard cannot read a clock",
     "c > 2", 1),
    ("c >= 1", "on q from T to S do { n' = 2; }", "'n' is not a clock of atom type A", "n'", 1),
    ("c >= 1", "invariant i at U provided (c <= 3)", "unknown place 'U'", "U provided", 1),
    ("c >= 1", "invariant i at S provided (c <= 3)\n    invariant i provided (n >= 0)",
     "duplicate invariant 'i'", "i provided", 1),
    ("c >= 1", "on q from T to S provided (c >= 1) do { n = 1; } resume (c != 2)",
     "the resume guard of the transition on q", "c != 2", 1),
    ("c >= 1", "priority pr p < q provided (c > 1)", "a priority guard cannot read a clock", "c > 1)", 1),
])
def test_timing_errors_are_located(guard, extra, message, needle, nth):
    located(ATOM.format(clock="clock c unit millisecond", guard=guard, extra=extra), message, needle, nth)


def test_clock_named_like_data_is_a_duplicate():
    text = ATOM.format(clock="clock n unit second", guard="n >= 1", extra="").replace("c = 0", "n = 0")
    located(text, "duplicate variable 'n'", "n unit")


@pytest.mark.parametrize("change, message", [
    ("on p from S to T provided (c >= 1) eager", "expected"),          # internal transitions take no urgency:
    ("clock c unit minute", "expected"),                                # nor units BIP2 does not have
])
def test_timed_syntax_errors(change, message):
    text = ATOM.format(clock="clock c unit millisecond", guard="c >= 1", extra="")
    if "minute" in change:
        text = text.replace("clock c unit millisecond", change)
        needle = "minute"
    else:
        text = text.replace("    \n  end", "    internal from T to S provided (n > 0) eager\n  end")
        needle = "eager\n  end"
    located(text, message, needle)


def test_writer_refuses_what_bip2_cannot_say():
    pkg = parse_file(TIMED / "resumer.bip")
    atom = pkg.atom_types[0]
    atom.clocks[0].unit = "fortnight"
    atom.transitions[1].urgency = "urgent"
    atom.transitions.append(type(atom.transitions[0])(None, ["DONE"], ["IDLE"], urgency="eager"))
    with pytest.raises(BipWriteError) as err:
        write_package(pkg)
    text = str(err.value)
    assert "unknown time unit 'fortnight'" in text
    assert "unknown urgency 'urgent'" in text
    assert "an internal transition has no urgency and no resume" in text


def test_rate_statement_prints_with_a_quote():
    pkg = parse_file(TIMED / "resumer.bip")
    assert "slow' = 0.5;" in write_package(pkg)
    assert Var("slow") not in pkg.atom_types[0].initial.action


def test_clock_out_of_order_gets_the_order_hint():
    text = ATOM.format(clock="clock c unit millisecond", guard="c >= 1", extra="").replace(
        "    place S, T\n", "    place S, T\n    clock late\n")
    with pytest.raises(DiagnosticError) as err:
        parse_text(text, "bad.bip")
    (d,) = err.value.diagnostics
    assert "data, clocks and ports, then place" in d.hint
