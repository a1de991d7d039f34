"""Every operator of the property language on a model small enough to answer by hand (Server.bip).

From IDLE the server can only take a request (S.req); then it works (S.work, to DONE) or fails (S.fail,
back to IDLE); from DONE it replies (S.reply, back to IDLE, served = (served + 1) % 2).
"""
import pytest

from runtime.diagnostics import DiagnosticError
from runtime.engine import flatten
from runtime.explore import StateSpace
from runtime.props import check, read_properties
from tests.verifykit import package


def verdict(text: str, name: str = "Server", root: str = "Main()"):
    pkg = package(name)
    (item,), _ = read_properties(text, "test.mcl", flatten(pkg, root))
    space = StateSpace(pkg, root, observed=item.observed, keep_edges=True)
    return check(space, item)


def holds(text: str) -> bool:
    return verdict(text).holds


# --- action formulas ---------------------------------------------------------------------------------

@pytest.mark.parametrize("formula, expected", [
    ('<"S.req"> true', True),  # exact label
    ('<"req"> true', True),  # the label after its leading module (instance) name
    ('<"work"> true', False),
    ('<"S.r*"> true', True),  # wildcard
    ('<"S.?eq"> true', True),
    ("<'S\\.r.q'> true", True),  # regular expression, whole label
    ("<optional 'r.q'> true", False),  # a regex must match the whole label
    ('<not "req"> true', False),
    ('<not "work"> true', True),
    ('<"req" and "S.req"> true', True),
    ('<"req" and "work"> true', False),
    ('<"work" or "req"> true', True),
    ("<true> true", True),
    ("<false> true", False),
])
def test_action_formulas(formula, expected):
    assert holds(formula) is expected


# --- regular formulas ---------------------------------------------------------------------------------

@pytest.mark.parametrize("formula, expected", [
    ('<"req" . "work"> true', True),
    ('<"req" . "reply"> true', False),
    ('<"work" | "req"> true', True),
    ('<"work" | "reply"> true', False),
    ('<true* . "reply"> true', True),
    ('<"req"*> true', True),  # zero steps already match
    ('<"req"+ . "work"> true', True),
    ('<"req" . "req"> true', False),
    ('<("req" . "fail")+ . "req" . "work" . "reply"> true', True),
    ('[true* . "work" . "req"] false', True),  # after work comes reply, never req
    ('[true* . "req" . "req"] false', True),
    ('["req" . ("work" | "fail")] false', False),
])
def test_regular_formulas(formula, expected):
    assert holds(formula) is expected


# --- state formulas -----------------------------------------------------------------------------------

@pytest.mark.parametrize("formula, expected", [
    ("true", True),
    ("false", False),
    ("T", True),
    ("F", False),
    ('not <"work"> true', True),
    ('<"req"> true and <"work"> true', False),
    ('<"req"> true or <"work"> true', True),
    ('<"work"> true implies false', True),
    ('["work"] false', True),
    ('["req"] false', False),
    ('["req"] <"work"> true', True),
    ("nu X. <true> X", True),  # an infinite path exists
    ("mu X. [true] X", False),  # not every path is finite
    ('mu X. <"reply"> true or <not "reply"> X', True),
    ('nu X. [not "reply"] X and <true> true', True),  # no deadlock on the way to a reply
    ("{S @ IDLE}", True),
    ("{S @ BUSY}", False),
    ('<"req"> {S @ BUSY and S.served == 0}', True),
    ("{not S @ DONE and S.served < 1}", True),
    ("{S.served}", False),  # a variable alone: != 0
    ('mu X. <"reply"> {S.served == 1} or <true> X', True),
    ("nu X. {S.served <= 1} and [true] X", True),
])
def test_state_formulas(formula, expected):
    assert holds(formula) is expected


# --- shorthands ---------------------------------------------------------------------------------------

def test_never():
    assert holds('never "work" . "fail"')
    v = verdict('never "S.reply"')
    assert v.holds is False and [s.label for s in v.trace] == ["S.req", "S.work", "S.reply"]


def test_precedes():
    assert holds('"req" precedes "work"')
    v = verdict('"work" precedes "req"')
    assert v.holds is False and v.evidence == "counterexample" and [s.label for s in v.trace] == ["S.req"]


def test_leads_to_within():
    assert holds('"work" leads to "reply" within 1 steps')
    v = verdict('"req" leads to "reply" within 2 steps')
    # req, then fail: two steps without a reply
    assert v.holds is False and [s.label for s in v.trace] == ["S.req", "S.fail", "S.req"]
    assert holds('"req" leads to "reply" or "fail" within 2 steps')


def test_invariant():
    assert holds("invariant S @ IDLE or S @ BUSY or S @ DONE")
    assert holds("invariant S.served <= 1")
    v = verdict("invariant S.served == 0")
    assert v.holds is False and [s.label for s in v.trace] == ["S.req", "S.work", "S.reply"]
    v = verdict("invariant not S @ DONE")
    assert v.holds is False and [s.label for s in v.trace] == ["S.req", "S.work"]


def test_a_name_that_starts_like_t_or_f_is_a_name_not_true_or_false():
    # T and F abbreviate true and false only as whole words: T265.main.overrun is an atom's path
    text = """
    package Flags
    port type Port()
    atom type Flag()
      data bool raised
      port Port set()
      place Off, On
      initial to Off do { raised = false; }
      on set from Off to On do { raised = true; }
    end
    compound type Main()
      component Flag T265()
      component Flag Fx()
    end
    end
    """
    from runtime.bip2 import parse_text

    pkg = parse_text(text, "Flags.bip")
    flat = flatten(pkg, "Main()")
    for prop, want in (("invariant not (T265 @ On)", False), ("invariant (T265.raised == F or T265 @ On) and T", True),
                       ("invariant Fx.raised == F", False)):
        (item,), _ = read_properties(prop, "test.mcl", flat)
        assert check(StateSpace(pkg, "Main()", observed=item.observed, keep_edges=True), item).holds is want, prop


def test_deadlock_free():
    assert holds("deadlock free")
    v = verdict("deadlock free", "Dining", "Table2()")
    assert v.holds is False and [s.label for s in v.trace] == ["left0", "left1"]


# --- evidence -----------------------------------------------------------------------------------------

def test_witness_of_a_diamond_is_a_shortest_path():
    v = verdict('<true* . "reply"> true')
    assert v.holds and v.evidence == "witness" and [s.label for s in v.trace] == ["S.req", "S.work", "S.reply"]


def test_witness_of_a_least_fixed_point_follows_its_derivation():
    v = verdict('mu X. <"reply"> true or <true> X')
    assert v.holds and [s.label for s in v.trace] == ["S.req", "S.work", "S.reply"]


def test_counterexample_of_a_greatest_fixed_point():
    v = verdict('nu X. [true] X and [ "reply" ] false')
    assert v.holds is False and v.evidence == "counterexample"
    assert [s.label for s in v.trace][-1] == "S.reply"


def test_universal_answers_show_no_single_path():
    v = verdict("nu X. <true> true and [true] X")
    assert v.holds and v.trace == []
    v = verdict('mu X. <optional "nothing"> true or <true> X')
    assert v.holds is False and v.trace == [] and "no path" in v.note


def test_several_properties_per_file_with_names():
    pkg = package("Server")
    items, warnings = read_properties('a: <"req"> true; b: never "work"; "req" precedes "work"', "f.mcl",
                                      flatten(pkg, "Main()"))
    assert [i.name for i in items] == ["a", "b", "property 3"]
    assert [i.property.pattern for i in items] == ["", "never", "precedes"]
    assert warnings == []


def test_label_matching_no_interaction_is_an_error_unless_optional():
    flat = flatten(package("Server"), "Main()")
    with pytest.raises(DiagnosticError) as info:
        read_properties('never "S.rpely"', "f.mcl", flat)
    (e,) = info.value.diagnostics
    assert (e.severity, str(e.span), e.message) == ("error", "f.mcl:1:7", '"S.rpely" matches no interaction label '
                                                                           "of the model")
    assert e.hint == 'nearest labels: "S.reply", "S.req". If matching nothing is intended, write optional "S.rpely"'
    (item,), warnings = read_properties('never optional "S.rpely"', "f.mcl", flat)
    assert warnings == [] and item.property.pattern == "never"


def test_limit_gives_an_inconclusive_verdict():
    pkg = package("Dining")
    (item,), _ = read_properties("deadlock free", "f.mcl", flatten(pkg, "Table3()"))
    v = check(StateSpace(pkg, "Table3()", keep_edges=True, max_states=3), item)
    assert v.holds is None and v.word == "inconclusive" and "budget" in v.note


def test_comments_in_property_files():
    assert holds('(* a comment *) <"req"> true -- another one')


def test_a_model_error_met_while_checking_is_reported():
    from tests.test_explore import COUNTER
    from tests.verifykit import text_space

    sp = text_space(COUNTER.replace("    data int n", '    @domain(range="0..30")\n    data int n'), keep_edges=True)
    (item,), _ = read_properties("deadlock free", "f.mcl", sp.engine.flat)
    v = check(sp, item)
    assert v.holds is None and v.word == "model error" and "left its declared domain 0..30" in v.error
