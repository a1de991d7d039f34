"""Plain values to C data and back, by the layouts the generator writes (genom2bip.back.c_types.c_layouts).

A layout is a small list: ``["b", "double"]`` a basic type, ``["str", 32]`` / ``["str", None]`` a bounded
or unbounded string, ``["arr", [2, 3], L]`` an array, ``["seq", 8, L]`` / ``["seq", None, L]`` a sequence,
``["opt", L]`` an optional, ``["ref", name]`` a named struct, union or enum (``types[name]``), ``["native",
name]`` an opaque pointer.  Values are the controller's plain data: dicts for structs, lists for sequences,
``str`` for strings and enumerators, ``None`` for an absent optional, ``{member: value}`` for a union.
"""
from __future__ import annotations

import ctypes
from typing import Any

BASE = {"bool": ctypes.c_bool, "char": ctypes.c_int8, "int8_t": ctypes.c_int8, "uint8_t": ctypes.c_uint8,
        "int16_t": ctypes.c_int16, "uint16_t": ctypes.c_uint16, "int32_t": ctypes.c_int32,
        "uint32_t": ctypes.c_uint32, "int64_t": ctypes.c_int64, "uint64_t": ctypes.c_uint64,
        "float": ctypes.c_float, "double": ctypes.c_double}
RELEASE = ctypes.CFUNCTYPE(None, ctypes.c_void_p)


class Layouts:
    """ctypes types for layouts (made once each) and the conversions, for one component's named types."""

    def __init__(self, types: dict[str, list]) -> None:
        self.types = types
        self.made: dict[str, Any] = {}

    def named(self, name: str) -> list:
        return self.types[name]

    def ctype(self, lay: list) -> Any:
        kind = lay[0]
        if kind == "b":
            return BASE[lay[1]]
        if kind == "str":
            return ctypes.c_char_p if lay[1] is None else ctypes.c_char * lay[1]
        if kind == "arr":
            t = self.ctype(lay[2])
            for n in reversed(lay[1]):
                t = t * n
            return t
        if kind == "native":
            return ctypes.c_void_p
        key = repr(lay)
        if key in self.made:
            return self.made[key]
        if kind == "ref":
            target = self.named(lay[1])
            if target[0] == "enum":
                return ctypes.c_uint32
            made = type(lay[1].replace("::", "_"), (ctypes.Structure,), {})
            self.made[key] = made
            if target[0] == "struct":
                made._fields_ = [(name, self.ctype(m)) for name, m in target[1]]
            else:  # a union: {_d, _u}
                members = type(lay[1].replace("::", "_") + "_u", (ctypes.Union,), {})
                members._fields_ = [(name, self.ctype(m)) for name, _, _, m in target[2]]
                made._fields_ = [("_d", self.ctype(target[1])), ("_u", members)]
            return made
        if kind == "seq":
            element = self.ctype(lay[2])
            if lay[1] is None:
                fields = [("_maximum", ctypes.c_uint32), ("_length", ctypes.c_uint32),
                          ("_buffer", ctypes.POINTER(element)), ("_release", ctypes.c_void_p)]
            else:
                fields = [("_maximum", ctypes.c_uint32), ("_length", ctypes.c_uint32), ("_buffer", element * lay[1])]
            made = type("sequence", (ctypes.Structure,), {"_fields_": fields})
        elif kind == "opt":
            made = type("optional", (ctypes.Structure,), {"_fields_": [("_present", ctypes.c_bool),
                                                                       ("_value", self.ctype(lay[1]))]})
        else:
            raise ValueError(f"unknown C layout {lay!r}")
        self.made[key] = made
        return made

    # -- to C -------------------------------------------------------------------------------------------------
    def fill(self, lay: list, value: Any, target: Any, keep: list) -> None:
        """Write ``value`` into the ctypes object ``target`` (a struct, array or sequence); ``keep`` holds buffers."""
        kind = lay[0]
        if kind == "arr":
            if _is_chars(lay) and isinstance(value, str):
                raw = value.encode()[: lay[1][0] - 1]
                ctypes.memmove(target, raw + b"\0", len(raw) + 1)
                return
            for k, item in enumerate((value or [])[: len(target)]):
                self._set_item(["arr", lay[1][1:], lay[2]] if len(lay[1]) > 1 else lay[2], target, k, item, keep)
            return
        if kind == "str":  # a bounded string: an array of char
            raw = (value or "").encode()[: lay[1] - 1]
            ctypes.memmove(target, raw + b"\0", len(raw) + 1)
            return
        if kind == "seq":
            items = list(value or [])
            if lay[1] is None:
                element = self.ctype(lay[2])
                buffer = (element * max(len(items), 1))()
                keep.append(buffer)
                for k, item in enumerate(items):
                    self._set_item(lay[2], buffer, k, item, keep)
                target._buffer = ctypes.cast(buffer, ctypes.POINTER(element))
                target._maximum = target._length = len(items)
                target._release = None
            else:
                items = items[: lay[1]]
                target._maximum, target._length = lay[1], len(items)
                for k, item in enumerate(items):
                    self._set_item(lay[2], target._buffer, k, item, keep)
            return
        if kind == "opt":
            target._present = value is not None
            if value is not None:
                self._set_field(lay[1], target, "_value", value, keep)
            return
        if kind == "ref":
            named = self.named(lay[1])
            if named[0] == "struct":
                for name, m in named[1]:
                    if isinstance(value, dict) and name in value:
                        self._set_field(m, target, name, value[name], keep)
            elif named[0] == "union" and isinstance(value, dict) and value:
                member, item = next(iter(value.items()))
                for name, labels, _, m in named[2]:
                    if name == member:
                        target._d = labels[0] if labels else 0
                        self._set_field(m, target._u, name, item, keep)
            return
        raise ValueError(f"cannot fill a {kind} in place")

    def scalar(self, lay: list, value: Any, keep: list) -> Any:
        """The Python value a scalar field or argument of this layout takes (enumerators by index, chars by code)."""
        kind = lay[0]
        if kind == "b":
            if lay[1] == "char":
                return ord(value[0]) if isinstance(value, str) and value else int(value or 0)
            if lay[1] in ("float", "double"):
                return float(value or 0.0)
            return bool(value) if lay[1] == "bool" else int(value or 0)
        if kind == "ref" and self.named(lay[1])[0] == "enum":
            values = self.named(lay[1])[1]
            return values.index(value) if value in values else int(value) if isinstance(value, int) else 0
        if kind == "str" and lay[1] is None:
            raw = ctypes.c_char_p((value or "").encode())
            keep.append(raw)
            return raw.value
        if kind == "native":
            return None
        raise ValueError(f"not a scalar layout {lay!r}")

    def is_scalar(self, lay: list) -> bool:
        return lay[0] in ("b", "native") or (lay[0] == "str" and lay[1] is None) or (
            lay[0] == "ref" and self.named(lay[1])[0] == "enum")

    def _set_field(self, lay: list, target: Any, name: str, value: Any, keep: list) -> None:
        if self.is_scalar(lay):
            setattr(target, name, self.scalar(lay, value, keep))
        elif lay[0] == "str":  # a char array member reads as a bytes copy: it is assigned whole
            setattr(target, name, (value or "").encode()[: lay[1] - 1])
        else:
            self.fill(lay, value, getattr(target, name), keep)

    def _set_item(self, lay: list, target: Any, k: int, value: Any, keep: list) -> None:
        if self.is_scalar(lay):
            target[k] = self.scalar(lay, value, keep)
        else:  # an element of an array is a view of its memory (a char array too): filled in place
            self.fill(lay, value, target[k], keep)

    def new(self, lay: list, value: Any, keep: list) -> Any:
        """A fresh ctypes object of this layout holding ``value``."""
        obj = self.ctype(lay)()
        if self.is_scalar(lay):
            obj.value = self.scalar(lay, value, keep)
        else:
            self.fill(lay, value, obj, keep)
        return obj

    # -- from C -----------------------------------------------------------------------------------------------
    def value(self, lay: list, obj: Any) -> Any:
        """The plain value a ctypes object (or a scalar read from one) of this layout holds."""
        kind = lay[0]
        if kind == "b":
            raw = obj.value if isinstance(obj, ctypes._SimpleCData) else obj
            if lay[1] == "char":
                return chr(raw & 0xFF) if raw else ""
            return raw
        if kind == "str":
            if lay[1] is None:
                raw = obj.value if isinstance(obj, ctypes.c_char_p) else obj
                return (raw or b"").decode(errors="replace")
            return bytes(obj).split(b"\0", 1)[0].decode(errors="replace")
        if kind == "native":
            return None
        if kind == "arr":
            if _is_chars(lay):
                return bytes(ctypes.string_at(ctypes.addressof(obj), len(obj))).split(b"\0", 1)[0].decode(
                    errors="replace")
            inner = ["arr", lay[1][1:], lay[2]] if len(lay[1]) > 1 else lay[2]
            return [self.value(inner, obj[k]) for k in range(len(obj))]
        if kind == "seq":
            n = min(obj._length, obj._maximum) if lay[1] is not None else obj._length
            if lay[1] is None and not obj._buffer:
                return []
            return [self.value(lay[2], obj._buffer[k]) for k in range(n)]
        if kind == "opt":
            return self.value(lay[1], obj._value) if obj._present else None
        if kind == "ref":
            named = self.named(lay[1])
            if named[0] == "enum":
                raw = obj.value if isinstance(obj, ctypes._SimpleCData) else obj
                return named[1][raw] if 0 <= raw < len(named[1]) else raw
            if named[0] == "struct":
                return {name: self.value(m, getattr(obj, name)) for name, m in named[1]}
            for name, labels, default, m in named[2]:
                if obj._d in labels:
                    return {name: self.value(m, getattr(obj._u, name))}
            for name, labels, default, m in named[2]:
                if default:
                    return {name: self.value(m, getattr(obj._u, name))}
            return {}
        raise ValueError(f"unknown C layout {lay!r}")

    def release(self, lay: list, obj: Any, ours: list) -> None:
        """Give back what a codel allocated in an unbounded sequence it grew (``_release``, usually free())."""
        if lay[0] == "seq" and lay[1] is None and obj._release:
            if not any(ctypes.addressof(b) == ctypes.cast(obj._buffer, ctypes.c_void_p).value for b in ours
                       if isinstance(b, ctypes.Array)):
                RELEASE(obj._release)(ctypes.cast(obj._buffer, ctypes.c_void_p))
        elif lay[0] == "ref" and self.named(lay[1])[0] == "struct":
            for name, m in self.named(lay[1])[1]:
                if m[0] in ("seq", "ref"):
                    self.release(m, getattr(obj, name), ours)


def _is_chars(lay: list) -> bool:
    return lay[0] == "arr" and len(lay[1]) == 1 and lay[2] == ["b", "char"]
