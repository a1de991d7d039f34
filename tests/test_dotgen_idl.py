"""The IDL part of the dotgen grammar: scopes, types, constants and exceptions, one feature per test."""
from __future__ import annotations

import pytest

from genom2bip.ir import (
    ArrayType,
    BaseType,
    EnumType,
    EnumValue,
    FixedType,
    NamedType,
    NativeType,
    OptionalType,
    SequenceType,
    StringType,
    StructType,
    Typedef,
    UnionType,
)
from genom2bip.parser import parse_text
from runtime.diagnostics import DiagnosticError


def errors(text: str) -> list:
    with pytest.raises(DiagnosticError) as info:
        parse_text(text, "t.gen")
    return info.value.diagnostics


def const(text: str, name: str = "c"):
    return parse_text(text, "t.gen").constants[name].value


def test_modules_scope_names_and_scoped_references_resolve():
    d = parse_text("""
        module a {
          module b { struct p { double x; }; };
          typedef b::p q;        // relative to a
          typedef ::a::b::p r;   // absolute
        };
        module a { typedef b::p s; };   // a module may be reopened
        typedef a::b::p t;
    """)
    assert set(d.types) == {"a::b::p", "a::q", "a::r", "a::s", "t"}
    assert isinstance(d.types["a::b::p"], StructType) and d.types["a::b::p"].name == "a::b::p"
    for name in ("a::q", "a::r", "a::s", "t"):
        assert d.types[name] == Typedef(name, NamedType("a::b::p"))


def test_inner_scope_shadows_outer_one():
    d = parse_text("struct p { long v; }; module m { struct p { double w; }; typedef p local; }; typedef p top;")
    assert d.types["m::local"].type == NamedType("m::p")
    assert d.types["top"].type == NamedType("p")


def test_unknown_type_names_are_kept_as_written_for_the_checks():
    d = parse_text("typedef nowhere::thing t;")
    assert d.types["t"].type == NamedType("nowhere::thing")


def test_typedef_with_several_declarators_and_arrays():
    d = parse_text("typedef long a, b[3], c[2][4];")
    assert d.types["a"].type == BaseType("long")
    assert d.types["b"].type == ArrayType(BaseType("long"), [3])
    assert d.types["c"].type == ArrayType(BaseType("long"), [2, 4])


@pytest.mark.parametrize("written,name", [
    ("short", "short"), ("long", "long"), ("long long", "long long"), ("unsigned short", "unsigned short"),
    ("unsigned long", "unsigned long"), ("unsigned long long", "unsigned long long"), ("float", "float"),
    ("double", "double"), ("char", "char"), ("boolean", "boolean"), ("octet", "octet"), ("any", "any"),
])
def test_base_types(written, name):
    assert parse_text(f"typedef {written} t;").types["t"].type == BaseType(name)


def test_struct_members_and_nested_struct_scope():
    d = parse_text("struct outer { struct inner { long a; } in1, in2[2]; double x, y; };")
    outer = d.types["outer"]
    assert [m.name for m in outer.members] == ["in1", "in2", "x", "y"]
    inner = d.types["outer::inner"]
    assert outer.members[0].type is inner and inner.members[0].type == BaseType("long")
    assert outer.members[1].type == ArrayType(inner, [2])
    assert outer.members[0].span.line == 1 and outer.members[0].span.column == 41


def test_union_with_switch_case_and_default():
    d = parse_text("""
        enum kind { K_INT, K_REAL, K_NONE };
        union value switch (kind) {
          case K_INT: long i;
          case K_REAL: case K_NONE: double r;
          default: char c;
        };
        union small switch (unsigned short) { case 1: long a; case 2 + 1: double b; };
    """)
    u = d.types["value"]
    assert isinstance(u, UnionType) and u.discriminator == NamedType("kind")
    assert [c.labels for c in u.cases] == [[0], [1, 2], ["default"]]
    assert [str(x) for x in u.cases[1].labels] == ["K_REAL", "K_NONE"]
    assert [c.member.name for c in u.cases] == ["i", "r", "c"]
    assert u.cases[1].member.type == BaseType("double")
    assert [c.labels for c in d.types["small"].cases] == [[1], [3]]
    assert d.types["small"].discriminator == BaseType("unsigned short")


def test_enum_declares_enumerators_in_the_enclosing_scope():
    d = parse_text("module m { enum color { RED, GREEN, BLUE }; const color c = GREEN; }; const m::color x = m::BLUE;")
    assert d.types["m::color"] == EnumType("m::color", ["RED", "GREEN", "BLUE"])
    assert d.constants["m::c"].value == EnumValue(1, "m::GREEN")
    assert d.constants["m::c"].value.name == "m::GREEN"
    assert d.constants["x"].value == 2 and str(d.constants["x"].value) == "m::BLUE"


def test_sequences_bounded_unbounded_and_nested():
    d = parse_text("""
        const long N = 4;
        typedef sequence<long> a;
        typedef sequence<double, N * 2> b;
        typedef sequence<sequence<long, 3> > c;
        typedef sequence<sequence<long>> d;   // '>>' is fine where no shift can follow
    """)
    assert d.types["a"].type == SequenceType(BaseType("long"), None)
    assert d.types["b"].type == SequenceType(BaseType("double"), 8)
    assert d.types["c"].type == SequenceType(SequenceType(BaseType("long"), 3), None)
    assert d.types["d"].type == SequenceType(SequenceType(BaseType("long"), None), None)


def test_strings_optionals_fixed_native_and_forward_declarations():
    d = parse_text("""
        typedef string s; typedef string<16> bs; typedef optional<double> od;
        typedef fixed<5, 2> money; native handle; struct later; struct later { long v; };
    """)
    assert d.types["s"].type == StringType(None)
    assert d.types["bs"].type == StringType(16)
    assert d.types["od"].type == OptionalType(BaseType("double"))
    assert d.types["money"].type == FixedType(5, 2)
    assert d.types["handle"] == NativeType("handle")
    assert [m.name for m in d.types["later"].members] == ["v"]


def test_exceptions_with_and_without_members():
    d = parse_text(
        "module m { exception e_plain, e_detail { double value; string<32> what; }; exception e_empty {}; };"
    )
    assert set(d.exceptions) == {"m::e_plain", "m::e_detail", "m::e_empty"}
    assert d.exceptions["m::e_plain"].members == []
    assert [(x.name, x.type) for x in d.exceptions["m::e_detail"].members] == [
        ("value", BaseType("double")), ("what", StringType(32))]


@pytest.mark.parametrize("expr,value", [
    ("1 + 2 * 3", 7), ("(1 + 2) * 3", 9), ("7 / 2", 3), ("-7 / 2", -3), ("7 % 3", 1), ("-7 % 3", -1),
    ("1 << 4", 16), ("256 >> 2", 64), ("6 & 3", 2), ("6 | 3", 7), ("6 ^ 3", 5), ("~0", -1), ("-(2 - 5)", 3),
    ("+4", 4), ("0x1F", 31), ("010", 8), ("1 | 2 ^ 3 & 4 << 1 + 1", 3), ("A * 2 + B", 13), ("(B - A) % 4", -2),
])
def test_integer_constant_expressions(expr, value):
    assert const(f"const long A = 5; const long B = A - 2; const long c = {expr};") == value


def test_float_boolean_char_and_string_constants():
    d = parse_text("""
        const double half = 1 / 2.0; const float e = 2.5e-1; const double n = 3;
        const boolean yes = TRUE; const boolean no = FALSE; const char ch = '\\n';
        const string<20> greeting = "hello, " "world";
    """)
    c = d.constants
    assert c["half"].value == 0.5 and c["e"].value == 0.25
    assert c["n"].value == 3.0 and isinstance(c["n"].value, float)
    assert c["yes"].value is True and c["no"].value is False
    assert c["ch"].value == "\n" and c["greeting"].value == "hello, world"
    assert c["greeting"].type == StringType(20)


def test_constants_through_typedef_and_in_array_sizes():
    d = parse_text("typedef long count; const count N = 3; struct s { long a[N + 1]; };")
    assert d.constants["N"].value == 3
    assert d.types["s"].members[0].type == ArrayType(BaseType("long"), [4])


def test_redefinition_in_the_same_scope_is_an_error():
    (e,) = errors("struct p { long a; };\ntypedef long p;")
    assert e.message == "'p' is already defined" and (e.span.line, e.span.column) == (2, 14)
    assert e.hint == "first defined at t.gen:1:8"


def test_duplicate_struct_member_is_an_error():
    (e,) = errors("struct p { long a; double a; };")
    assert e.message == "duplicate member 'a' in struct 'p'" and e.span.column == 27


def test_division_by_zero_is_reported_at_the_expression():
    (e,) = errors("const long a = 1;\nconst long b = 4 / (a - 1);")
    assert e.message == "division by zero in constant expression"
    assert (e.span.file, e.span.line, e.span.column) == ("t.gen", 2, 16)


@pytest.mark.parametrize("text,message", [
    ("const long c = X + 1;", "unknown constant 'X'"),
    ("const long c = 1 << -1;", "negative shift count -1 in constant expression"),
    ("const long c = 5 % 0;", "division by zero in constant expression"),
    ("const long c = 1.5;", "constant 'c' has type long but its value 1.5 is not an integer"),
    ("const double c = 2.0 % 1;", "operator '%' needs integer operands, not floating-point 2.0"),
    ("const string c = \"a\" + \"b\";", "operator '+' cannot be applied to a string"),
    ("const boolean c = 1;", "constant 'c' has type boolean but its value 1 is not TRUE or FALSE"),
    ("const long c = 09;", "invalid octal constant '09'"),
    ("typedef long c[2 - 2];", "array size must be a positive integer, not 0"),
    ("typedef sequence<long, -1> c;", "sequence bound must be a positive integer, not -1"),
])
def test_bad_constant_expressions(text, message):
    (e,) = errors(text)
    assert e.message == message and e.span.line == 1
