"""What the controller does with every value a codel writes or is handed: the test a poster value takes
(``schema.checker``) says what ``schema.problems`` says, and a clone shares nothing that can change.

``checker`` answers True only where ``problems`` finds nothing; it may answer False where ``problems`` then finds
nothing (it leaves subclasses of int or float, and sums past the largest float, to ``problems``).  On values made
of plain ints, finite floats of ordinary size, strings, lists and dicts, the two agree exactly, which the random
schemas and values below check, values that fit the schema and values one change away from it alike.
"""
from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st

from runtime.controller.schema import ITEMS_CHECKED, checker, problems

NAMES = ("a", "b", "c")
TYPES_OF = {"T": {"type": "object", "properties": {"x": {"type": "integer", "minimum": 0, "maximum": 9},
                                                   "y": {"type": "array", "items": {"type": "number"}}},
                  "required": ["x"], "additionalProperties": False},
            "E": {"type": "string", "enum": ["on", "off"]}}

scalars = st.one_of(
    st.just({"type": "number"}),
    st.just({"type": "integer"}),
    st.builds(lambda lo, hi: {"type": "integer", "minimum": lo, "maximum": hi},
              st.integers(-5, 0), st.integers(0, 5)),
    st.builds(lambda hi: {"type": "number", "maximum": hi}, st.floats(-2, 2)),
    st.builds(lambda n: {"type": "string", "maxLength": n}, st.integers(0, 4)),
    st.just({"type": "string"}),
    st.just({"type": "boolean"}),
    st.just({"$ref": "E"}),
    st.just({"$ref": "T"}),
    st.just({"type": "integer", "enum": [1, 3]}),
    st.just({"$ref": "missing"}),
    st.just({}),
)


def _array(items):
    return st.builds(lambda few, many: {"type": "array", "items": items,
                                        **({"minItems": few} if few is not None else {}),
                                        **({"maxItems": many} if many is not None else {})},
                     st.none() | st.integers(0, 2), st.none() | st.integers(2, 4))


def _object(children):
    return st.builds(lambda props, required, closed, most: {
        "type": "object", "properties": dict(zip(NAMES, props)), "required": list(NAMES[:required]),
        **({"additionalProperties": False} if closed else {}), **({"maxProperties": most} if most else {})},
        st.lists(children, min_size=1, max_size=3), st.integers(0, 2), st.booleans(), st.none() | st.just(1))


schemas = st.recursive(scalars, lambda children: st.one_of(
    children.flatmap(_array), _object(children), st.lists(children, min_size=1, max_size=2).map(
        lambda options: {"anyOf": options})), max_leaves=6)

plain = st.recursive(
    st.one_of(st.none(), st.booleans(), st.integers(-12, 12),
              st.floats(-4, 4, allow_nan=False, allow_infinity=False), st.sampled_from(["", "on", "off", "abcde"]),
              st.sampled_from([math.inf, -math.inf, math.nan])),
    lambda children: st.one_of(st.lists(children, max_size=5),
                               st.dictionaries(st.sampled_from(NAMES + ("x", "y", "z")), children, max_size=4)),
    max_leaves=10)


def fitting(schema, draw, off):
    """A value ``problems`` accepts for ``schema``, or, while ``off[0]`` allows it, one that a single bound, member or
    length puts outside it (so that each rule is what decides, not one of several)."""
    def away() -> int:
        if off[0] and draw(st.integers(0, 3)) == 0:
            off[0] = False
            return 1
        return 0

    while "$ref" in schema:
        schema = TYPES_OF.get(schema["$ref"], {})
    if "anyOf" in schema:
        return fitting(draw(st.sampled_from(schema["anyOf"])), draw, off)
    kind = schema.get("type")
    if "enum" in schema:
        return draw(st.sampled_from(schema["enum"])) if not away() else draw(plain)
    if kind == "integer":
        lo, hi, d = schema.get("minimum", -9), schema.get("maximum", 9), away()
        return draw(st.sampled_from([lo - 1, hi + 1])) if d else draw(st.integers(lo, hi))
    if kind == "number":
        hi = schema.get("maximum", 9)
        return hi + 0.5 if away() else draw(st.floats(-9, hi, allow_nan=False, allow_infinity=False)
                                           | st.integers(-9, min(0, math.floor(hi))))
    if kind == "string":
        n = schema.get("maxLength", 5)
        return "a" * (n + 1) if away() else draw(st.text("ab", max_size=n))
    if kind == "boolean":
        return draw(st.booleans())
    if kind == "array":
        few, many = schema.get("minItems", 0), schema.get("maxItems", 3)
        n = draw(st.sampled_from([x for x in (few - 1, many + 1) if x >= 0] or [many])) if away() else \
            draw(st.integers(few, many))
        return [fitting(schema["items"], draw, off) for _ in range(n)]
    if kind == "object":
        props = schema["properties"]
        keys = [k for k in props if k in schema.get("required", [])] or list(props)[:1]
        keys = keys[:schema.get("maxProperties", 3)]
        if away() and keys:
            keys = keys[1:]  # a required member left out (or one fewer where none is required)
        out = {k: fitting(props[k], draw, off) for k in keys}
        missing = [k for k in schema.get("required", []) if k not in props]
        out.update({k: draw(plain) for k in missing})
        if away():
            out[draw(st.sampled_from(("z",) + NAMES))] = draw(plain)  # a member the schema may not have
        return out
    return draw(plain)


@st.composite
def cases(draw):
    schema = draw(schemas)
    value = fitting(schema, draw, [True]) if draw(st.integers(0, 3)) else draw(plain)
    return schema, value


@settings(max_examples=400, deadline=None)  # each example is microseconds; 400 draw every schema kind many times
@given(cases())
def test_the_fast_test_says_what_problems_says(case):
    schema, value = case
    found = problems(value, schema, TYPES_OF, "p")
    assert checker(schema, TYPES_OF)(value) == (found == []), found


@settings(max_examples=200, deadline=None)
@given(cases(), st.sampled_from([True, 7, 2.5, 10**400, 1e308]))
def test_where_the_fast_test_is_cautious_problems_decides(case, odd):
    """Subclasses of int (a bool is not an integer), ints past any float, sums past the largest float: the fast test
    may say False where ``problems`` then finds nothing, never True where it finds something."""
    schema, value = case
    for v in (odd, [odd, odd], [1e308, 1e308], {"a": odd}):
        if checker(schema, TYPES_OF)(v):
            assert problems(v, schema, TYPES_OF, "p") == []


def test_a_long_list_of_numbers_is_checked_to_the_same_item_as_problems_checks():
    schema = {"type": "array", "items": {"type": "number"}}
    bad_late = [0.5] * ITEMS_CHECKED + [math.nan]  # past what either looks at
    bad_early = [0.5] * (ITEMS_CHECKED - 1) + [math.nan]
    assert checker(schema, {})(bad_late) and problems(bad_late, schema, {}, "p") == []
    assert not checker(schema, {})(bad_early)
    assert problems(bad_early, schema, {}, "p") == [f"p[{ITEMS_CHECKED - 1}]: nan is not a finite number"]
    assert not checker(schema, {})([0.5, "0.5"]) and not checker(schema, {})([True])
    assert not checker({"type": "array", "items": {"type": "integer"}}, {})([1, 2.0])


def test_a_type_that_contains_itself_is_tested_without_end():
    types = {"L": {"type": "object", "properties": {"next": {"anyOf": [{"type": "null"}, {"$ref": "L"}]},
                                                  "v": {"type": "integer"}}}}
    good = {"v": 1, "next": {"v": 2, "next": {"v": 3, "next": None}}}
    bad = {"v": 1, "next": {"v": 2, "next": {"v": "3", "next": None}}}
    test = checker({"$ref": "L"}, types)
    assert test(good) and problems(good, {"$ref": "L"}, types, "p") == []
    assert not test(bad) and problems(bad, {"$ref": "L"}, types, "p") != []


def test_a_clone_shares_nothing_that_can_change_with_the_value_it_copies():
    """The controller hands codels clones of posters and ids: a codel changing its copy, at any depth, changes nothing
    stored (a list of scalars is copied in one call, a list holding lists or dicts member by member)."""
    from runtime.controller.data import clone

    stored = {"scan": [0.5, 1, None, "x", True], "rows": [[1, 2], [3]], "poses": [{"x": 1.0}], "n": 3}
    copy = clone(stored)
    assert copy == stored
    copy["scan"][0] = 9.0
    copy["rows"][0].append(7)
    copy["poses"][0]["x"] = 2.0
    copy["n"] = 4
    assert stored == {"scan": [0.5, 1, None, "x", True], "rows": [[1, 2], [3]], "poses": [{"x": 1.0}], "n": 3}
