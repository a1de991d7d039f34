"""The Verimag compiler's warnings, mirrored by the validator: non-determinism, dead code, unbound ports."""
from pathlib import Path

from genom2bip.generate import model_of
from genom2bip.parser import parse_paths
from genom2bip.rules import all_rules
from runtime.bip2.lint import exclusive
from runtime.bip2.reader import _read
from runtime.bip2.validate import validate
from runtime.diagnostics import Reporter, SourceCache
from runtime.model import Binary, Const, Unary, Var

ROOT = Path(__file__).resolve().parents[1]

MODEL = """package P
  port type Port()
  atom type A()
    data int x
    export port Port p()
    export port Port q()
    place S, T, U, V
    initial to S do { x = 0; }
    on p from S to T do { x = 1; }
    internal from T to S provided (x == 0)
    {mark}internal from T to U provided (x != 0)
    on p from U to S
    on q from V to S
  end
  connector type R(Port a)
    define a
  end
  compound type C()
    component A a()
    component A b()
    connector R c(a.p)
    connector R d(a.q)
    connector R e(b.p)
  end
end
"""


def warnings(text: str):
    reporter = Reporter(SourceCache())
    _read(text, "w.bip", reporter)
    assert not reporter.has_errors, [d.render() for d in reporter.diagnostics]
    return [(d.span.line, d.message) for d in reporter.diagnostics if d.severity == "warning"]


def test_each_warning_at_its_line():
    found = warnings(MODEL.replace("{mark}", ""))
    assert found == [
        (11, "atom type A: transitions 'internal from T to S' and 'internal from T to U' may both be enabled "
             "from the same place (non-determinism)"),
        (13, "atom type A: transition 'on q from V to S' cannot be executed (dead code): no run marks its "
             "source places"),
        (20, "component 'b' in compound type C has unconnected port q"),
    ]


def test_suppress_warning_silences_as_bipc_does():
    text = MODEL.replace("{mark}", "@SuppressWarning(nondeterminism)\n    ")
    assert [m for _, m in warnings(text) if "non-determinism" in m] == []
    whole = "@SuppressWarning(deadcode, unboundcomponentport)\n" + MODEL.replace("{mark}", "")
    assert [m for _, m in warnings(whole)] == [
        "atom type A: transitions 'internal from T to S' and 'internal from T to U' may both be enabled "
        "from the same place (non-determinism)"]


def test_two_unguarded_transitions_are_reported():
    text = MODEL.replace("{mark}", "").replace("internal from T to S provided (x == 0)", "internal from T to S")
    text = text.replace("internal from T to U provided (x != 0)", "internal from T to U")
    assert (11, "atom type A: transitions 'internal from T to S' and 'internal from T to U' compete from the "
                "same place with no guard (non-determinism)") in warnings(text)


def test_exclusive_reads_the_shape_of_guards():
    x, b = Var("outcome"), Var("aborted")
    eq = lambda k: Binary("==", x, Const(k))  # noqa: E731
    ne = lambda k: Binary("!=", x, Const(k))  # noqa: E731
    assert exclusive(eq(0), eq(1))
    assert exclusive(Binary("&&", eq(2), b), Binary("&&", eq(2), Unary("!", b)))
    assert exclusive(eq(1), Binary("&&", ne(0), ne(1)))
    assert not exclusive(eq(1), Binary("&&", ne(0), ne(2)))
    assert not exclusive(Binary(">=", x, Const(1)), eq(0))  # true, but not by shape
    assert not exclusive(None, eq(0))


def test_generated_dala_has_no_warning_and_its_silenced_choices_are_exclusive():
    dala = ROOT / "descriptions" / "dala"
    description = parse_paths([dala])
    package, _, _ = model_of(description, "dala", all_rules(description, dala / "rules.yaml", Reporter()))
    assert [d.message for d in validate(package)] == []  # no warning either
    pairs = 0
    for atom in package.atom_types:
        for i, t in enumerate(atom.transitions):
            if any(a.name == "SuppressWarning" for a in t.annotations):
                for u in atom.transitions[:i]:
                    if u.port == t.port and set(u.sources) & set(t.sources):
                        assert exclusive(u.guard, t.guard), (atom.name, t, u)
                        pairs += 1
    assert pairs > 50
