"""Print BIP model objects as the Python expressions that build them.

The generated package constructs its model with ``runtime.model`` classes in
plain, readable Python (``Transition("exec_plan", ["PLAN"], ["PLAN_YIELD"], ...)``)
instead of embedding a blob of text: a reader sees the automaton in the code.
Fields left at their default are omitted; required fields are positional.
"""
from __future__ import annotations

from dataclasses import MISSING, fields, is_dataclass
from typing import Any

from runtime.diagnostics import Span

WIDTH = 100


def _default_of(f) -> Any:
    if f.default is not MISSING:
        return f.default
    if f.default_factory is not MISSING:  # type: ignore[misc]
        return f.default_factory()  # type: ignore[misc]
    return MISSING


def constructor(obj: Any, indent: int = 0) -> str:
    """``obj`` as Python source, wrapped to stay under ~100 columns."""
    flat = _flat(obj)
    if len(flat) + indent <= WIDTH:
        return flat
    return _wrapped(obj, indent)


def _args(obj: Any) -> list[tuple[str | None, Any]]:
    out: list[tuple[str | None, Any]] = []
    keyword = False
    for f in fields(obj):
        if not f.init or f.name == "span" or f.type == "Span":
            continue
        value = getattr(obj, f.name)
        if isinstance(value, Span):
            continue
        default = _default_of(f)
        if default is not MISSING and value == default:
            keyword = True  # once a field is skipped, the later ones must be named
            continue
        if f.kw_only or default is not MISSING or keyword:
            keyword = True
            out.append((f.name, value))
        else:
            out.append((None, value))
    return out


def _flat(obj: Any) -> str:
    if is_dataclass(obj) and not isinstance(obj, type):
        inner = ", ".join((f"{k}={_flat(v)}" if k else _flat(v)) for k, v in _args(obj))
        return f"{type(obj).__name__}({inner})"
    if isinstance(obj, list):
        return "[" + ", ".join(_flat(v) for v in obj) + "]"
    if isinstance(obj, tuple):
        items = [_flat(v) for v in obj]
        return "(" + ", ".join(items) + ("," if len(items) == 1 else "") + ")"
    if isinstance(obj, dict):
        return "{" + ", ".join(f"{_flat(k)}: {_flat(v)}" for k, v in obj.items()) + "}"
    return repr(obj)


def _wrapped(obj: Any, indent: int) -> str:
    pad = " " * (indent + 4)
    if is_dataclass(obj) and not isinstance(obj, type):
        parts = []
        for k, v in _args(obj):
            text = constructor(v, indent + 4)
            parts.append(f"{pad}{k}={text}" if k else f"{pad}{text}")
        return f"{type(obj).__name__}(\n" + ",\n".join(parts) + ",\n" + " " * indent + ")"
    if isinstance(obj, (list, tuple)):
        open_, close = ("[", "]") if isinstance(obj, list) else ("(", ")")
        parts = [f"{pad}{constructor(v, indent + 4)}" for v in obj]
        return open_ + "\n" + ",\n".join(parts) + ",\n" + " " * indent + close
    return _flat(obj)
