"""Every syntax and validation error of the BIP2 reader: its words and its file:line:column."""
import pytest

from runtime.bip2 import parse_text, validate
from runtime.diagnostics import DiagnosticError
from runtime.model import AtomType, InitialTransition, Package, Transition, Var


def errors(text: str):
    with pytest.raises(DiagnosticError) as err:
        parse_text(text, "bad.bip")
    return err.value.diagnostics


def where(text: str, needle: str, nth: int = 1) -> tuple[int, int]:
    """1-based line and column of the nth occurrence of ``needle`` in ``text``; with a '|' in the needle,
    of the character after it ("x <|)" is the ')' after "x <")."""
    before, bar, _ = needle.partition("|")
    pos = -1
    for _ in range(nth):
        pos = text.index(needle.replace("|", ""), pos + 1)
    if bar:
        pos += len(before)
    line = text.count("\n", 0, pos) + 1
    return line, pos - (text.rfind("\n", 0, pos) + 1) + 1


def assert_one(text: str, message: str, needle: str, nth: int = 1):
    diags = errors(text)
    assert len(diags) == 1, [d.render() for d in diags]
    d = diags[0]
    assert message in d.message, d.render()
    assert (d.span.file, d.span.line, d.span.column) == ("bad.bip", *where(text, needle, nth)), d.render()
    return d


BASE = """package P
  port type Port()
  port type IntPort(int v)
  extern function int f(int)
  atom type A(int k)
    data int x = 0
    export data int y
    export port Port p()
    export port IntPort q(x)
    place S, T
    initial to S
    on p from S to T provided (x < k) do { x = f(x); }
    on q from T to S
  end
  connector type R(Port a, Port b)
    define a b
  end
  connector type C(IntPort a, IntPort b)
    data int t
    export port IntPort e(t)
    define a' b
    on a b provided (a.v > 0) up { t = a.v; } down { b.v = t; }
  end
  compound type K()
    component A a1(1), a2(2)
    connector R r(a1.p, a2.p)
    connector C c(a1.q, a2.q)
    priority pr r:* < c:a1.q, a2.q provided (a1.y > 0)
    export port c.e as e
    export data a1.y as y
  end
end
"""


def test_base_is_valid():
    assert parse_text(BASE).compound_types[0].name == "K"


# ---------------------------------------------------------------------- syntax
SYNTAX = [
    # (old, new, message, needle in the new text)
    ("    place S, T\n    initial to S\n", "    initial to S\n    place S, T\n",
     "expected ',', '@', 'as', 'clock', 'data', 'export', 'extern', 'place' or 'port', found 'initial'",
     "initial to S"),
    ("    on q from T to S\n", "    on q from T to S\n    data int z\n",
     "expected ", "data int z"),
    ("port type Port()", "port type Port", "expected '(', found 'port'", "port type IntPort"),
    ("provided (x < k)", "provided (x < k < 2)", "expected an operator or ')', found '<'", "< 2"),
    ("provided (x < k)", "provided (x <)", "expected an expression, found ')'", "x <|)"),
    ("do { x = f(x); }", "do { x = f(x) }", "expected an operator or ';', found '}'", "}", 1),
    ("data int x = 0", "data int place = 0", "expected a name, found 'place'", "place = 0"),
    ("    export port c.e as e\n", "    export port c.e as e\n    component A a3(3)\n",
     "expected '@', 'end' or 'export', found 'component'", "component A a3"),
    ("    priority pr r:* < c:a1.q, a2.q provided (a1.y > 0)\n",
     "    priority pr provided (a1.y > 0) r:* < c:a1.q, a2.q\n",
     "expected a name or '*', found 'provided'", "provided (a1.y"),
    ("    on q from T to S\n", "    on q from T to S\n    on p from T to", "expected a name, found 'end'", "end\n"),
    ("x = f(x);", "x = f(x) $;", "unexpected character '$'", "$"),
    ("define a b", 'define a b "oops', "unterminated string", '"oops'),
    ("end\n", "/* never closed\n", "unterminated comment", "/* never"),
    ("do { x = f(x); }", "do { if (x > 0) then x = 1; fi; }", "expected a name, 'if' or '}', found ';'", "; }"),
    ("provided (x < k)", "provided (x << k)", "expected an expression, found '<'", "< k)"),
    ("end\n", "", "expected '@', 'atom', 'compound', 'connector', 'const', 'data', 'end', 'extern' or 'port', "
                  "found the end of the file", "  end\n", -1),
]


@pytest.mark.parametrize("case", SYNTAX, ids=[c[2][:40] for c in SYNTAX])
def test_syntax_errors(case):
    old, new, message, needle, *nth = case
    nth = nth[0] if nth else 1
    count = -1 if old == "end\n" else 1
    text = BASE[::-1].replace(old[::-1], new[::-1], 1)[::-1] if count == -1 else BASE.replace(old, new, 1)
    diags = errors(text)
    assert len(diags) == 1, [d.render() for d in diags]
    d = diags[0]
    assert message in d.message, d.render()
    if nth == -1:  # end of file: the last non-blank character
        stripped = text.rstrip()
        assert (d.span.line, d.span.column) == (stripped.count("\n") + 1, len(stripped) - stripped.rfind("\n"))
    else:
        assert (d.span.line, d.span.column) == where(text, needle, nth), d.render()


def test_syntax_error_hints():
    text = BASE.replace("provided (x < k)", "provided (x < k < 2)")
    assert "comparisons do not chain" in errors(text)[0].hint
    text = BASE.replace("    place S, T\n    initial to S\n", "    initial to S\n    place S, T\n")
    assert "the order is fixed" in errors(text)[0].hint
    text = BASE.replace("provided (x < k)", "provided (x << k)")
    assert "no shift operators" in errors(text)[0].hint
    text = BASE.replace("do { x = f(x); }", "do { if (x > 0) then x = 1; fi; }")
    assert "no ';' after 'fi'" in errors(text)[0].hint
    text = BASE.replace("data int x = 0", "data int place = 0")
    assert "'place' is a reserved word of BIP2" in errors(text)[0].hint
    text = BASE.replace("data int x = 0", "data int x = 0, error")  # an extern port's event policy
    assert "'error' is a reserved word of BIP2" in errors(text)[0].hint
    text = BASE.replace("priority pr r:* < c:a1.q, a2.q provided (a1.y > 0)",
                        "priority pr provided (a1.y > 0) r:* < c:*")
    assert "provided (...) comes after the rule" in errors(text)[0].hint


def test_rendered_error_quotes_the_line_with_a_caret():
    text = BASE.replace("initial to S", "initial to S2")
    with pytest.raises(DiagnosticError) as err:
        parse_text(text, "bad.bip")
    rendered = str(err.value)
    assert "bad.bip:11:16: error: unknown place 'S2' in atom type A" in rendered
    assert "    initial to S2\n" in rendered and "               ^^" in rendered


# ---------------------------------------------------------------------- validation
VALIDATION = [
    ("initial to S", "initial to S2", "unknown place 'S2' in atom type A", "S2"),
    ("on q from T to S", "on q from T to U", "unknown place 'U' in atom type A", "U\n"),
    ("on p from S to T", "on pp from S to T", "unknown port 'pp' in atom type A", "pp"),
    ("provided (x < k)", "provided (x < kk)", "unknown variable 'kk' in atom type A", "kk"),
    ("do { x = f(x); }", "do { z = f(x); }", "unknown variable 'z' in atom type A", "z ="),
    ("do { x = f(x); }", "do { k = f(x); }", "cannot assign to parameter 'k' in atom type A", "k = f"),
    ("do { x = f(x); }", "do { x = g(x); }", "unknown extern function 'g'", "g(x)"),
    ("do { x = f(x); }", "do { x = f(x, 1); }", "extern function 'f' takes 1 argument(s), 2 given", "f(x, 1)"),
    ("export port IntPort q(x)", "export port IntPort q(w)", "unknown variable 'w' bound to port 'q'", "w)"),
    ("export port IntPort q(x)", "export port IntPort q()", "port type IntPort carries 1 value(s), 0 bound", "q()"),
    ("export port Port p()", "export port Prt p()", "unknown port type 'Prt'", "Prt"),
    ("export port Port p()", "export port A p()", "'A' is a atom type, not a port type", "A p()"),
    ("data int x = 0", "data intt x = 0", "unknown data type 'intt'", "intt"),
    ("    export data int y\n", "    export data int y\n    data int x\n", "duplicate variable 'x' in atom type A",
     "data int |x\n"),
    ("    place S, T\n", "    place S, T, S\n", "duplicate place 'S' in atom type A", "T, |S\n"),
    ("  port type IntPort(int v)\n", "  port type IntPort(int v)\n  port type Port()\n",
     "duplicate type name 'Port' in package P", "Port()", 2),
    ("    define a b\n  end\n  connector type C",
     "    define a b x\n  end\n  connector type C", "'x' in define is not a port parameter of connector type R",
     "x\n"),
    ("    define a b\n  end\n  connector type C",
     "    define a\n  end\n  connector type C", "port parameter 'b' of connector type R does not appear in its define",
     "b)"),
    ("on a b provided (a.v > 0) up { t = a.v; } down { b.v = t; }", "on b provided (b.v > 0) down { b.v = t; }",
     "'on b' is not an interaction that the define", "on b"),
    ("on a b provided (a.v > 0)", "on a b provided (r.v > 0)", "'r.v': 'r' is not a port parameter", "r.v"),
    ("on a b provided (a.v > 0)", "on a b provided (a.w > 0)", "port type IntPort carries no 'w'", "a.w"),
    ("up { t = a.v; }", "up { t = u; }", "unknown variable 'u' in connector type C, on a b", "u;"),
    ("component A a1(1), a2(2)", "component B a1(1), a2(2)", "unknown atom or compound type 'B'", "B a1"),
    ("component A a1(1), a2(2)", "component A a1(1), a2()", "atom type A takes 1 parameter(s), 0 given", "a2()"),
    ("connector R r(a1.p, a2.p)", "connector R r(a1.p, a2.p)\n    connector R a1(a1.p, a2.p)",
     "duplicate component or connector name 'a1'", "a1(a1.p"),
    ("connector R r(a1.p, a2.p)", "connector R r(a1.p, a2.p)\n    connector R r2(a1.p, a1.p)",
     "a1.p is given twice to connector 'r2'", "a1.p, |a1.p"),
    ("connector R r(a1.p, a2.p)", "connector R r(a1.p, a2.p, a2.q)",
     "connector type R has 2 port parameter(s), 3 port(s) given", "r(a1"),
    ("connector R r(a1.p, a2.p)", "connector R r(a1.p, a2.q)",
     "port type mismatch: parameter 'b' of connector type R is Port, but a2.q is IntPort", "a2.q"),
    ("connector R r(a1.p, a2.p)", "connector Rx r(a1.p, a2.p)", "unknown connector type 'Rx'", "Rx"),
    ("connector R r(a1.p, a2.p)", "connector R r(a1.p, a3.p)",
     "no component or connector named 'a3' in compound type K", "a3.p"),
    ("connector R r(a1.p, a2.p)", "connector R r(a1.p, a2.z)",
     "component 'a2' (atom type A) has no port 'z'", "a2.z"),
    ("priority pr r:* <", "priority pr rr:* <", "unknown connector 'rr' in priority pr of compound type K", "rr:*"),
    ("c:a1.q, a2.q provided", "c:a1.q, a2.p provided", "a2.p is not a port of connector 'c'", "a2.p provided"),
    ("provided (a1.y > 0)", "provided (a1.x > 0)", "data 'x' of component 'a1' (atom type A) is not exported",
     "a1.x"),
    ("export port c.e as e", "export port c.f as e", "connector 'c' exports port 'e', not 'f'", "c.f"),
    ("export data a1.y as y", "export data a1.x as y", "is not exported", "a1.x as"),
    ("    export data a1.y as y\n", "    export data a1.y as y\n    export data a2.y as y\n",
     "duplicate exported data 'y' in compound type K", "y\n  end\nend", 1),
    ("  extern function int f(int)\n", "  extern function int f(int)\n  const data int N\n",
     "constant 'N' needs a value", "N\n"),
    ("    data int x = 0\n", "    data int x = 0\n    data const int z\n", "const data 'z' needs a value", "z\n"),
    ("    on q from T to S\n", "    on q from T to S\n    priority both * < *\n",
     "priority both of atom type A has '*' on both sides", "both"),
    ("    on q from T to S\n", "    on q from T to S\n    priority bad p < z\n", "unknown port 'z' in priority bad",
     "z\n"),
    ("    priority pr r:* <", "    priority pr *:* < *:*\n    priority pr2 r:* <",
     "priority pr of compound type K has '*:*' on both sides", "pr *"),
    ("do { x = f(x); }", "do { x = a.v; }", "dotted data references are allowed only in connectors", "a.v"),
    ("  compound type K()\n", "  compound type L() component K k() end\n  compound type K()\n    component L l()\n",
     "compound type L contains itself (L -> K -> L)", "L l()"),
    ("data int x = 0", "data int x = 0, minute", "'minute' is a reserved word of BIP2", "minute"),
    ("export port c.e as e", "export port Port e is c.e",
     "exported port 'e' of compound type K is Port, but c.e is IntPort", "c.e\n"),
    # Verimag: noSideEffectInGuards
    ("provided (x < k)", "provided (f(x) < k)", "atom type A: the guard calls 'f', whose parameters are not all const",
     "f(x) <"),
    ("on a b provided (a.v > 0)", "on a b provided (f(a.v) > 0)",
     "connector type C, on a b: the guard calls 'f', whose parameters are not all const", "f(a.v)"),
    ("provided (a1.y > 0)", "provided (f(a1.y) > 0)", "priority pr of compound type K: the guard calls 'f'", "f(a1.y)"),
    ("    export port Port p()\n", "    export port Port p()\n    port Port p3(), p4() as pp\n",
     "port 'p3' of atom type A is merged as 'pp' but not exported", "pp\n"),
    ("    export port Port p()\n", "    export port Port p()\n    export port Port p3(), p4() as p\n",
     "exported port 'p' of atom type A has the name of port 'p'", "as |p"),
    # Verimag: priorityContradictMaximalProgress
    ("    priority pr r:* <", "    priority big c:a1.q, a2.q < c:a2.q\n    priority pr r:* <",
     "priority big of compound type K contradicts maximal progress: c:a1.q, a2.q contains c:a2.q", "big c:"),
    # Verimag: connectorDoesNotBindTheSameComponentMoreThanOnce
    ("  compound type K()\n    component A a1(1), a2(2)\n",
     "  compound type L()\n    component A b1(1), b2(2)\n"
     "    export port b1.p as p1\n    export port b2.p as p2\n  end\n"
     "  compound type K()\n    component A a1(1), a2(2)\n    component L l()\n    connector R twice(l.p1, l.p2)\n",
     "connector 'twice' in compound type K binds component 'l' more than once", "twice("),
]


@pytest.mark.parametrize("case", VALIDATION, ids=[c[2][:50] for c in VALIDATION])
def test_validation_errors(case):
    old, new, message, needle, *nth = case
    assert old in BASE, old
    text = BASE.replace(old, new, 1)
    assert_one(text, message, needle, nth[0] if nth else 1)


def test_a_merged_atom_port_is_seen_by_its_merged_name_only():
    text = BASE.replace("    export port Port p()\n", "    export port Port p(), p2() as pp\n")
    text = text.replace("connector R r(a1.p, a2.p)", "connector R r(a1.pp, a2.p2)")
    assert_one(text, "port 'p2' of component 'a2' (atom type A) is exported as 'pp'", "a2.p2")


def test_several_errors_are_reported_together_in_source_order():
    text = BASE.replace("initial to S", "initial to S2").replace("component A a1(1), a2(2)", "component B a1(1), a2(2)")
    text = text.replace("define a' b", "define a' b x")
    diags = errors(text)
    messages = [d.message for d in diags]
    assert any("unknown place 'S2'" in m for m in messages)
    assert any("'x' in define" in m for m in messages)
    assert any("unknown atom or compound type 'B'" in m for m in messages)
    lines = [d.span.line for d in diags]
    assert lines == sorted(lines)
    with pytest.raises(DiagnosticError) as err:
        parse_text(text, "bad.bip")
    assert str(err.value).rstrip().endswith(f"{len(diags)} errors")


def test_validate_names_the_declaration_of_a_model_built_in_code():
    pkg = Package("P", atom_types=[AtomType("A", places=["S"], initial=InitialTransition(["S"]),
                                            transitions=[Transition(None, ["S"], ["X"], Var("nope"))])])
    messages = [d.message for d in validate(pkg)]
    assert messages == ["unknown place 'X' in atom type A", "unknown variable 'nope' in atom type A"]


def test_a_guard_may_call_a_function_whose_parameters_are_all_const():
    text = BASE.replace("extern function int f(int)", "extern function int f(const int)")
    text = text.replace("provided (x < k)", "provided (f(x) < k)")
    assert parse_text(text).extern_functions[0].param_const == [True]
    hint = errors(BASE.replace("provided (x < k)", "provided (f(x) < k)"))[0].hint
    assert hint == "declare it extern function int f(const int)"


BINDS_THROUGH_SUB_CONNECTORS = """package P
  port type Port()
  connector type R(Port a, Port b)
    define a b
  end
  connector type RX(Port a, Port b)
    export port Port e()
    define a b
  end
  atom type A()
    export port Port p()
    place S
    initial to S
    on p from S to S
  end
  compound type K()
    component A c1(), c2(), c3()
    connector RX x(c1.p, c2.p), y(c2.p, c3.p)
    connector R top(x.e, y.e)
  end
end
"""


def test_a_connector_reaches_a_component_twice_through_its_sub_connectors():
    """Verimag's own case: c2 is bound once by x and once by y; only the connector that fires is checked."""
    d = assert_one(BINDS_THROUGH_SUB_CONNECTORS, "connector 'top' in compound type K binds component 'c2' more than "
                                                 "once", "top(")
    assert d.hint == "join those ports in a connector inside the component and export its port"
    fixed = BINDS_THROUGH_SUB_CONNECTORS.replace("connector R top(x.e, y.e)", "connector R top(x.e, c3.p)")
    fixed = fixed.replace("connector RX x(c1.p, c2.p), y(c2.p, c3.p)", "connector RX x(c1.p, c2.p), y(c2.p, c3.p)")
    assert parse_text(fixed).compound_types[0].name == "K"


def test_an_interaction_block_may_have_no_guard_and_no_action():
    """``on a b`` alone is legal BIP2 (bipc accepts it): the interaction, with no guard and nothing to do."""
    text = BASE.replace("on a b provided (a.v > 0) up { t = a.v; } down { b.v = t; }", "on a b")
    pkg = parse_text(text)
    spec = pkg.connector_type("C").interactions[0]
    assert (spec.ports, spec.guard, spec.up, spec.down) == (["a", "b"], None, [], [])
    from genom2bip.back.bip2 import write_package
    written = write_package(pkg)
    assert "    on a b\n" in written and parse_text(written) == pkg
def test_an_expression_nested_without_bound_is_located_not_an_internal_error():
    chain = "+".join(["1"] * 3000)
    text = ("package P\n  port type Port()\n  atom type A()\n    data int x\n    port Port p()\n    place S\n"
            f"    initial to S do {{ x = {chain}; }}\n    on p from S to S\n  end\nend\n")
    [d] = errors(text)
    assert (d.span.line, d.message) == (7, "nested more than 200 operators deep here")
    assert parse_text(text.replace(chain, "+".join(["1"] * 150)), "ok.bip").atom_types[0].name == "A"
