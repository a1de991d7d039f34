"""The BIP2 writer: Verimag declaration order, reserved words, refusals that write nothing, atomic files."""
import copy
from pathlib import Path

import pytest

from genom2bip.back.bip2 import RESERVED, BipWriteError, bip_identifier, write_package
from genom2bip.generate import write_bip_file
from runtime.bip2 import parse_file, parse_text
from runtime.bip2.syntax import parser
from runtime.model import (
    Annotation, Assign, AtomType, Binary, ComponentInstance, CompoundType, ConnectorInstance, ConnectorParam,
    ConnectorType, Const, DataDecl, DefineGroup, DefinePort, If, InitialTransition, InteractionPattern,
    Package, PortRef, PortType, Priority, Transition, Unary, Var,
)

FIXTURES = sorted((Path(__file__).parent / "fixtures" / "bip" / "roundtrip").glob("*.bip"))


# ---------------------------------------------------------------------- reserved words
def test_reserved_words_cover_every_grammar_version():
    for word in ("error", "at", "clock", "unit", "sync", "async", "resume", "lazy", "eager", "delayable",
                 "invariant", "remember", "ignore", "package", "atom", "on", "port", "data", "define", "if", "fi",
                 "true", "int", "refine", "operator", "nanosecond", "day", "from", "to", "up", "down", "as"):
        assert word in RESERVED


@pytest.mark.parametrize("name, renamed", [
    ("error", "error_"), ("clock", "clock_"), ("goto", "goto"), ("pause::s", "pause__s"), ("3d", "_3d"),
    ("NDD.GoTo", "NDD_GoTo"), ("", "_"), ("from", "from_"), ("été", "_t_"),
])
def test_bip_identifier(name, renamed):
    assert bip_identifier(name) == renamed
    assert bip_identifier(renamed) == renamed  # already valid names are left alone


# ---------------------------------------------------------------------- declaration order of the output
ATOM_ORDER = {"export": 0, "data": 0, "port": 0, "place": 1, "initial": 2, "on": 3, "internal": 3, "priority": 4}
CONNECTOR_ORDER = {"data": 0, "export": 1, "define": 2, "on": 3}
COMPOUND_ORDER = {"component": 0, "connector": 0, "priority": 1, "export": 2}


def _tokens(text):
    return list(parser().lex(text))


def order_problems(text: str) -> list[str]:
    """Where the written text breaks the Verimag order rules (empty when it keeps them)."""
    problems = []
    toks = _tokens(text)
    block, rank, braces = None, 0, 0
    for i, tok in enumerate(toks):
        value, keyword = tok.value, tok.type != "ID"
        if tok.type == "LBRACE":
            braces += 1
        elif tok.type == "RBRACE":
            braces -= 1
        if not keyword or braces:
            continue
        if value == "type" and i > 0 and toks[i - 1].value in ("atom", "connector", "compound"):
            block, rank = (
                {"atom": ATOM_ORDER, "connector": CONNECTOR_ORDER, "compound": COMPOUND_ORDER}[toks[i - 1].value],
                0,
            )
            continue
        if value == "type" and toks[i - 1].value == "port" and toks[i + 2].type != "LPAR":
            problems.append(f"port type {toks[i + 1]} without parentheses")
        if value == "end":
            block = None
        elif block is not None and value in block and not (value == "connector" and toks[i + 1].value == "type"):
            if block[value] < rank:
                problems.append(f"line {tok.line}: '{value}' after a later section")
            rank = max(rank, block[value])
        if value == "priority" and block is COMPOUND_ORDER:
            j = i
            while toks[j].type != "LT":
                if toks[j].value == "provided":
                    problems.append(f"line {tok.line}: compound priority guard before the rule")
                j += 1
    return problems


@pytest.mark.parametrize("path", FIXTURES, ids=lambda p: p.stem)
def test_output_keeps_the_declaration_order(path):
    text = write_package(parse_file(path))
    assert order_problems(text) == []


def test_order_checker_sees_violations():
    bad = ("package P port type T atom type A() place S data int x initial to S end "
           "compound type K() priority p a:* < b:* provided (true) component A a() end end")
    assert len(order_problems(bad)) == 3


@pytest.mark.parametrize("path", FIXTURES, ids=lambda p: p.stem)
def test_output_uses_no_reserved_word_as_identifier(path):
    text = write_package(parse_file(path))
    names = [t.value for t in _tokens(text) if t.type == "ID"]
    assert names and not [n for n in names if n in RESERVED]


def test_output_is_deterministic_and_indented():
    model = parse_file(FIXTURES[0])
    first = write_package(model)
    assert first == write_package(copy.deepcopy(model))
    lines = first.splitlines()
    assert lines[0].startswith("package ") and lines[-1] == "end"
    assert all(line == "" or line.startswith("  ") or line in ("end",) or line.startswith(("package", "@"))
               for line in lines)
    assert "\n\n\n" not in first and not any(line != line.rstrip() for line in lines)


def test_annotation_values_are_quoted_only_when_needed():
    model = Package("P", annotations=[Annotation("cpp", {"include": "a.hpp", "mode": "fast", "flag": "",
                                                         "enabled": "true", "kw": "place", "n": "2"})],
                    port_types=[PortType("T")])
    text = write_package(model)
    assert text.startswith('@cpp(include="a.hpp", mode=fast, flag, enabled=true, kw="place", n="2")\npackage P\n')
    assert parse_text(text) == model


# ---------------------------------------------------------------------- refusals
def atom(**changes) -> AtomType:
    a = AtomType("A", data=[DataDecl("int", "x")], places=["S"], initial=InitialTransition(["S"]),
                 transitions=[Transition(None, ["S"], ["S"], None, [Assign(Var("x"), Const(1))])])
    for k, v in changes.items():
        setattr(a, k, v)
    return a


def package(*atoms, connectors=(), compounds=()) -> Package:
    return Package("P", port_types=[PortType("T")], atom_types=list(atoms), connector_types=list(connectors),
                   compound_types=list(compounds))


def refused(model) -> list[str]:
    with pytest.raises(BipWriteError) as err:
        write_package(model)
    assert str(err.value).startswith(f"cannot write package {model.name} as BIP2")
    return err.value.problems


def conn(**changes) -> ConnectorType:
    c = ConnectorType("C", [ConnectorParam("T", "a")], DefineGroup([DefinePort("a")]))
    for k, v in changes.items():
        setattr(c, k, v)
    return c


def compound(**changes) -> CompoundType:
    k = CompoundType("K", components=[ComponentInstance("A", "a")],
                     connectors=[ConnectorInstance("C", "c", [PortRef("a", "p")])])
    for k_, v in changes.items():
        setattr(k, k_, v)
    return k


@pytest.mark.parametrize("model, problem", [
    (package(atom(data=[DataDecl("int", "error")])),
     "atom type A, data error: data 'error' uses the reserved word 'error'; rename it consistently "
     "(bip_identifier gives 'error_')"),
    (package(atom(places=["S", "at"], initial=InitialTransition(["S"]))),
     "atom type A: place 'at' uses the reserved word 'at'"),
    (package(atom(name="pause::s")), "atom type pause::s: atom type 'pause::s' is not a BIP2 identifier"),
    (package(atom(transitions=[Transition("clock", ["S"], ["S"])])),
     "atom type A, transition on clock: port 'clock' uses the reserved word 'clock'"),
    (package(atom(transitions=[Transition(None, ["S"], ["S"], Var("sync"))])),
     "atom type A, internal transition: variable 'sync' uses the reserved word 'sync'"),
    (package(atom(transitions=[Transition(None, ["S"], ["S"], None, [If(Var("x"), ())])])),
     "atom type A, internal transition: an 'if' with an empty 'then' branch"),
    (package(atom(transitions=[Transition(None, ["S"], ["S"], Binary("<<", Var("x"), Const(1)))])),
     "atom type A, internal transition: BIP2 has no binary operator '<<'"),
    (package(atom(transitions=[Transition(None, ["S"], ["S"], Unary("+", Var("x")))])),
     "atom type A, internal transition: BIP2 has no unary operator '+'"),
    (package(atom(data=[DataDecl("float", "x", Const(float("nan")))])),
     "atom type A, data x: no BIP2 literal for the float nan"),
    (package(atom(places=[])), "atom type A: no place (BIP2 needs 'place ...')"),
    (package(atom(initial=None)), "atom type A: no initial transition (BIP2 needs 'initial to ...')"),
    (package(atom(), connectors=[conn(params=[])]), "connector type C: no port parameter"),
    (package(atom(), connectors=[conn(define=DefineGroup([DefinePort("a")], trigger=True))]),
     "connector type C: the whole define expression cannot be a trigger"),
    (package(atom(), connectors=[conn(data=[DataDecl("int", "t", exported=True)])]),
     "connector type C, data t: connector data cannot be exported"),
    (package(atom(), connectors=[conn()], compounds=[compound(components=[], connectors=[])]),
     "compound type K: no component and no connector"),
    (package(atom(), connectors=[conn()],
             compounds=[compound(connectors=[ConnectorInstance("C", "c", [PortRef("a", "p")], [Const(1)])])]),
     "compound type K, connector c: BIP2 connectors take no data arguments"),
    (package(atom(), connectors=[conn()], compounds=[compound(priorities=[
        Priority("p", InteractionPattern("*", [PortRef("a", "p")]), InteractionPattern("c", None))])]),
     "compound type K, priority p: '*' (any connector) takes no port list: write *:*"),
    (package(atom(), connectors=[conn()], compounds=[compound(components=[ComponentInstance("A", "unit")])]),
     "compound type K, component unit: component 'unit' uses the reserved word 'unit'"),
    (package(atom(annotations=[Annotation("cpp", {"resume": "x"})])),
     "atom type A: key of annotation @cpp 'resume' uses the reserved word 'resume'"),
])
def test_writer_refuses_what_bip2_cannot_say(model, problem):
    problems = refused(model)
    assert any(p.startswith(problem) for p in problems), problems


def test_every_problem_is_listed_at_once():
    model = package(atom(data=[DataDecl("int", "error")], places=["at"], initial=InitialTransition(["at"]),
                         transitions=[]))
    problems = refused(model)
    assert len(problems) == 3  # data 'error', place 'at', and 'at' again as the initial target


def test_refused_model_writes_nothing(tmp_path):
    bad = package(atom(data=[DataDecl("int", "error")]))
    with pytest.raises(BipWriteError):
        write_bip_file(bad, tmp_path)
    assert list(tmp_path.iterdir()) == []
    good = package(atom())
    path = write_bip_file(good, tmp_path)
    before = path.read_text()
    with pytest.raises(BipWriteError):
        write_bip_file(bad, tmp_path)
    assert path.read_text() == before and [p.name for p in tmp_path.iterdir()] == ["P.bip"]


def test_a_refused_model_names_its_problem_and_keeps_the_previous_file(tmp_path):
    (tmp_path / "P.bip").write_text("previous\n")
    bad = package(atom(data=[DataDecl("int", "error")]))
    with pytest.raises(BipWriteError) as err:
        write_bip_file(bad, tmp_path)
    assert str(err.value) == "cannot write package P as BIP2 (1 problem(s)):\n  - atom type A, data error: data " \
        "'error' uses the reserved word 'error'; rename it consistently (bip_identifier gives 'error_')"
    assert (tmp_path / "P.bip").read_text() == "previous\n" and [p.name for p in tmp_path.iterdir()] == ["P.bip"]


def test_writing_again_replaces_the_file(tmp_path):
    path = write_bip_file(package(atom()), tmp_path)
    path2 = write_bip_file(package(atom(name="B")), tmp_path)
    assert path == path2 and "atom type B()" in path.read_text()
    assert [p.name for p in tmp_path.iterdir()] == ["P.bip"]


def test_renamed_model_is_accepted():
    a = atom(data=[DataDecl("int", bip_identifier("error"))], places=[bip_identifier("at")],
             initial=InitialTransition([bip_identifier("at")]), transitions=[])
    text = write_package(package(a))
    assert "data int error_" in text and "place at_" in text


def test_a_new_file_gets_the_permissions_the_umask_gives(tmp_path):
    import os

    umask = os.umask(0o022)
    try:
        path = write_bip_file(package(atom()), tmp_path)
    finally:
        os.umask(umask)
    assert path.stat().st_mode & 0o777 == 0o644
