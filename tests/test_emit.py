"""The line writer every generator uses: blocks indent, fresh names are scoped, each language its syntax."""
from __future__ import annotations

from runtime.engine.emit import CWriter, PythonWriter


def test_python_blocks_indent_and_fresh_names_restart_in_each_scope():
    w = PythonWriter()
    with w.block("def f(x)"):
        with w.names():
            a, b = w.fresh("t"), w.fresh("t")
            w(f"{a} = x")
            w.if_then(f"{a} > 1", f"{b} = 2")
        with w.names():
            w(f"{w.fresh('t')} = 3")
        with w.if_("x", comment="first"):
            w("y = 1")
        with w.if_("not x", first=False):
            w("y = 2")
        w.else_then("y = 3")
    w()
    assert w.source() == (
        "def f(x):\n"
        "    t0 = x\n"
        "    if t0 > 1:\n"
        "        t1 = 2\n"
        "    t0 = 3\n"
        "    if x:  # first\n"
        "        y = 1\n"
        "    elif not x:\n"
        "        y = 2\n"
        "    else:\n"
        "        y = 3\n"
        "\n"
    )


def test_c_blocks_close_and_statements_end_with_semicolons():
    w = CWriter()
    with w.block("static void f(V *L)", "port a.p"):
        w.stmt("V m = L[0]")
        with w.block(""):
            w.if_then("m & 2", "fail(2, 0)")
        with w.if_("m"):
            w.stmt("m = 0")
        w.else_then("m = 1")
    assert w.source() == (
        "static void f(V *L) {  /* port a.p */\n"
        "    V m = L[0];\n"
        "    {\n"
        "        if (m & 2) fail(2, 0);\n"
        "    }\n"
        "    if (m) {\n"
        "        m = 0;\n"
        "    }\n"
        "    else m = 1;\n"
        "}\n"
    )


def test_fresh_names_resume_after_a_nested_scope():
    w = CWriter()
    first = w.fresh("c")
    with w.names():
        inner = w.fresh("c")
    assert (first, inner, w.fresh("c")) == ("c0", "c0", "c1")
