"""Static errors of the property language: each with its message and file:line:column."""
import pytest

from runtime.diagnostics import DiagnosticError
from runtime.engine import flatten
from runtime.props import read_properties
from tests.verifykit import package


def errors(text: str) -> list[tuple[str, str]]:
    flat = flatten(package("Server"), "Main()")
    with pytest.raises(DiagnosticError) as info:
        read_properties(text, "bad.mcl", flat)
    return [(str(d.span), d.message) for d in info.value.diagnostics if d.severity == "error"]


def one(text: str) -> tuple[str, str]:
    (err,) = errors(text)
    return err


def test_syntax_error_says_what_was_expected():
    where, message = one('<"S.req"> ')
    assert where == "bad.mcl:1:10"
    assert message.startswith("unexpected end of the file; expected ")
    assert "a label in double quotes" in message and "mu" in message


def test_syntax_error_on_a_later_line():
    where, message = one('a: <"S.req"> true;\nb: [ "S.req" ] false )')
    assert where == "bad.mcl:2:22" and message.startswith("unexpected ')'")


def test_unexpected_character():
    where, message = one('<"S.req"> true $')
    assert where == "bad.mcl:1:16" and "unexpected character '$'" in message


def test_unbound_variable():
    assert one('mu X. <"S.req"> Y') == ("bad.mcl:1:17", "unbound variable Y: no enclosing 'mu Y .' or 'nu Y .'")


def test_non_monotone_negation():
    where, message = one('mu X. not <"S.req"> X')
    assert where == "bad.mcl:1:21"
    assert message == ("X occurs under an odd number of negations (the negation at 1:7): mu X (at 1:4) is not "
                       "monotone")


def test_implies_counts_as_a_negation():
    where, message = one('nu X. (X implies <"S.req"> true)')
    assert where == "bad.mcl:1:8" and "odd number of negations" in message


def test_alternation_between_explicit_fixed_points():
    where, message = one('nu X. mu Y. (<"S.req"> X or <"S.work"> Y)')
    assert where == "bad.mcl:1:7"
    assert message == ("alternation: mu Y depends on X, bound by nu X at 1:4; only alternation-free formulas can "
                       "be checked")


def test_alternation_through_an_iteration():
    where, message = one('mu X. [ "S.req"* ] X')
    assert where == "bad.mcl:1:9"
    assert message.startswith('alternation: the iteration "S.req"* (a greatest fixed point, nu) depends on X')


def test_label_where_a_state_formula_is_expected():
    where, message = one('"S.req" and true')
    assert where == "bad.mcl:1:1"
    assert message.startswith('"S.req" is an action formula, but a state formula is expected here')


def test_regular_operator_under_or():
    where, message = one('[ "S.req" or ("S.work" . "S.reply") ] false')
    assert where == "bad.mcl:1:15"
    assert message.startswith("'or' combines action formulas, not regular ones: use '|'")


def test_regular_operator_in_a_state_formula():
    where, message = one("true . false")
    assert where == "bad.mcl:1:1" and "belongs inside <...> or [...]" in message


def test_variable_used_as_an_action():
    assert one("never req") == ("bad.mcl:1:7", "'req' is not an action: labels are written in double quotes (\"req\")")


def test_invalid_regular_expression():
    where, message = one("never 'S.(req'")
    assert where == "bad.mcl:1:7" and message.startswith("invalid regular expression 'S.(req'")


def test_true_cannot_name_a_variable():
    assert one("mu T. true") == ("bad.mcl:1:4", "'T' means true and cannot name a variable")


def test_unknown_atom_place_and_variable():
    where, message = one("invariant Q @ IDLE")
    assert where == "bad.mcl:1:11" and message == "no atom named Q"
    where, message = one("invariant S @ IDEL")
    assert where == "bad.mcl:1:11"
    assert message == "atom S (Server) has no place IDEL; places: IDLE, BUSY, DONE"
    where, message = one("{S.serve == 1}")
    assert where == "bad.mcl:1:2" and message == "atom S (Server) has no variable serve; variables: served"


def test_bound_of_leads_to():
    where, message = one('"S.req" leads to "S.reply" within 0 steps')
    assert where == "bad.mcl:1:1" and "between 1 and" in message


def test_property_defined_twice():
    where, message = one('a: true; a: false')
    assert where == "bad.mcl:1:10" and message == "property a is defined twice (first at 1:1)"


def test_empty_file():
    assert one("(* nothing here *)\n-- nor here\n") == ("bad.mcl:1:1", "no property in this file")


def test_all_errors_of_a_file_are_reported_together():
    found = errors('a: mu X. <"S.req"> Y;\nb: invariant S @ NOWHERE')
    assert [w for w, _ in found] == ["bad.mcl:1:20", "bad.mcl:2:14"]


def test_errors_render_with_the_line_and_a_caret():
    flat = flatten(package("Server"), "Main()")
    with pytest.raises(DiagnosticError) as info:
        read_properties('mu X. <"S.req"> Y', "bad.mcl", flat)
    assert info.value.render().splitlines() == [
        "bad.mcl:1:17: error: unbound variable Y: no enclosing 'mu Y .' or 'nu Y .'",
        '    mu X. <"S.req"> Y',
        "                    ^",
    ]


def test_a_binary_property_file_is_located(tmp_path):
    from runtime.props import read_property_file

    bad = tmp_path / "bad.mcl"
    bad.write_bytes(b'[ true* ] true;\n-- r\xe9sum\xe9\n')
    with pytest.raises(DiagnosticError) as info:
        read_property_file(bad, flatten(package("Server"), "Main()"))
    [d] = info.value.diagnostics
    assert (str(d.span), d.message) == (f"{bad}:2:5", "not a UTF-8 text file: byte 0xe9 cannot be read")
    assert "    -- r\ufffdsum\ufffd\n        ^" in info.value.render()


def test_a_misspelt_label_is_an_error_with_the_nearest_labels():
    assert errors('a: [ true* . "S.rpely" ] false;\nb: <"req"> true;\nc: "S.req" precedes "S.wrok"') == [
        ("bad.mcl:1:14", '"S.rpely" matches no interaction label of the model'),
        ("bad.mcl:3:21", '"S.wrok" matches no interaction label of the model'),
    ]


def test_a_pattern_matching_nothing_needs_optional():
    assert errors("never 'S\\.abort.*'") == [("bad.mcl:1:7", "'S\\.abort.*' matches no interaction label of the model")]
    flat = flatten(package("Server"), "Main()")
    items, warnings = read_properties("never optional 'S\\.abort.*'; [true* . optional \"*:abort\"] false", "ok.mcl",
                                      flat)
    assert len(items) == 2 and warnings == []


def test_optional_stands_only_before_a_label_or_a_pattern():
    where, message = one('[ optional true ] false')
    assert where == "bad.mcl:1:12" and message.startswith("unexpected 'true'")


def test_verify_stops_on_a_misspelt_label_instead_of_saying_holds(tmp_path, capsys):
    from genom2bip.cli import main
    from tests.verifykit import NDD

    prop = tmp_path / "fly.mcl"
    prop.write_text('[ true* . "NDD.Fly:start" ] false\n')
    assert main(["verify", str(NDD), "--property", str(prop)]) == 1
    out, err = capsys.readouterr()
    assert "holds" not in out
    assert err.startswith(f'{prop}:1:11: error: "NDD.Fly:start" matches no interaction label of the model\n'
                          '    [ true* . "NDD.Fly:start" ] false\n'
                          '              ^^^^^^^^^^^^^^^\n'
                          '    hint: nearest labels: "NDD.Stop:start", "NDD.GoTo:start", "NDD.SetSpeed:start". '
                          'If matching nothing is intended, write optional "NDD.Fly:start"\n')


@pytest.mark.parametrize("text,where", [
    ("(* open\n[ true* ] true\n", "bad.mcl:1:1"),
    ('-- a (* in a line comment\n[ true* ] true; (* closed *) <"S.req"> true; (* the rest\n"x"', "bad.mcl:2:46"),
])
def test_an_unclosed_comment_is_named_where_it_opens(text, where):
    assert one(text) == (where, "unterminated comment: this '(*' is never closed by '*)'")


def test_comment_markers_inside_labels_are_not_comments():
    where, message = one('<"S.req"> true; <"(*"> true')
    assert (where, message) == ("bad.mcl:1:18", '"(*" matches no interaction label of the model')


def test_a_formula_nested_too_deeply_is_an_error_not_an_internal_one():
    chain = " and ".join(['<"S.req"> true'] * 600)
    ((where, message),) = errors(chain)
    assert where.startswith("bad.mcl:1:") and message == "the formula is nested more than 200 operators deep here"
    nested = '<"S.req">' * 400 + "true"
    assert errors(nested) == [("bad.mcl:1:1775", "the formula is nested more than 200 operators deep here")]
    flat = flatten(package("Server"), "Main()")
    items, _ = read_properties(" and ".join(['<"S.req"> true'] * 100), "ok.mcl", flat)
    assert len(items) == 1
