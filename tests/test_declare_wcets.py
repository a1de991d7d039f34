"""Declared WCETs rewritten in a description's text: only each named codel's ``wcet`` changes, or nothing at all."""
from __future__ import annotations

import pytest

from genom2bip.declare_wcets import WcetEditError, codels, set_wcets
from genom2bip.loading import read_description

ARM = """/* arm: a fixture with each kind of codel declaration; a comment; with semicolons */
component arm {
  exception e_far;
  ids { long n; double target; };
  port out long Pos;

  task servo {
    period 10 ms;
    codel <start> armInit(ids out n) yield move;
    codel <move> armMove(ids inout n, // the wcet keyword in a comment; and a ';'
                         port out Pos) yield pause::move wcet 2 ms;
  };

  attribute SetTarget(in target = 0.0 : "where to go") {
    validate armCheck(local in target);
    throw e_far;
  };

  activity Go() {
    task servo;
    codel <start> armGo(ids in target) yield ether wcet 500 us  ;
  };
};
"""


def _write(tmp_path):
    path = tmp_path / "arm.gen"
    path.write_text(ARM)
    return path


def _declared(tmp_path) -> dict[str, float | None]:
    return {name: (p.seconds * 1e3 if p.seconds is not None else None)
            for name, p in codels(read_description([tmp_path])).items()}


def test_each_codel_is_named_by_its_owner_and_says_what_it_declares(tmp_path):
    _write(tmp_path)
    assert _declared(tmp_path) == {"arm.servo.armInit": None, "arm.servo.armMove": 2.0,
                                   "arm.SetTarget.armCheck": None, "arm.Go.armGo": 0.5}


def test_only_the_wcet_of_each_named_codel_changes(tmp_path):
    path = _write(tmp_path)
    changed = set_wcets([tmp_path], {"arm.servo.armInit": 1, "arm.servo.armMove": 3, "arm.SetTarget.armCheck": 1.5,
                                     "arm.Go.armGo": 4})
    assert changed == [path]
    assert _declared(tmp_path) == {"arm.servo.armInit": 1.0, "arm.servo.armMove": 3.0,
                                   "arm.SetTarget.armCheck": 1.5, "arm.Go.armGo": 4.0}
    want = (ARM.replace("yield move;", "yield move wcet 1 ms;")
            .replace("yield pause::move wcet 2 ms;", "yield pause::move wcet 3 ms;")
            .replace("validate armCheck(local in target);", "validate armCheck(local in target) wcet 1.5 ms;")
            .replace("yield ether wcet 500 us  ;", "yield ether wcet 4 ms;"))
    assert path.read_text() == want  # the comments, the layout and every other line as they were


def test_a_wcet_already_declared_leaves_the_file_untouched(tmp_path):
    path = _write(tmp_path)
    before = path.stat().st_mtime_ns
    assert set_wcets([tmp_path], {"arm.servo.armMove": 2}) == []
    assert path.read_text() == ARM and path.stat().st_mtime_ns == before


@pytest.mark.parametrize("wanted, message", [
    ({"arm.servo.armInit": 1, "arm.servo.armFly": 2, "arm.Go.nothing": 3},
     "no such codel in {dir}: arm.servo.armFly, arm.Go.nothing"),
    ({"arm.servo.armInit": 1, "arm.Go.armGo": 0}, "a WCET is a positive number of ms: arm.Go.armGo = 0"),
    ({"arm.servo.armInit": float("nan")}, "a WCET is a positive number of ms: arm.servo.armInit = nan"),
])
def test_a_codel_that_is_not_there_or_a_wcet_that_is_not_one_changes_nothing(tmp_path, wanted, message):
    path = _write(tmp_path)
    with pytest.raises(WcetEditError) as err:
        set_wcets([tmp_path], wanted)
    assert str(err.value) == message.format(dir=tmp_path)
    assert path.read_text() == ARM
    assert sorted(p.name for p in tmp_path.iterdir()) == ["arm.gen"]  # no temporary file left


def test_a_declaration_without_its_semicolon_is_located_and_nothing_is_written(tmp_path, monkeypatch):
    import genom2bip.declare_wcets as declare

    path = _write(tmp_path)
    place = codels(read_description([tmp_path]))["arm.Go.armGo"]
    # the parser's place for a codel, as a description changed since it was read would give
    monkeypatch.setattr(declare, "codels", lambda d: {"arm.Go.armGo": declare.Place(
        type(place.span)(place.span.file, place.span.line - 1, place.span.column), None)})
    with pytest.raises(WcetEditError) as err:
        set_wcets([tmp_path], {"arm.Go.armGo": 2})
    assert str(err.value) == (f"{path}:{place.span.line - 1}:{place.span.column}: cannot find the declaration of "
                              "codel arm.Go.armGo (a codel name, then ';')")
    assert path.read_text() == ARM
