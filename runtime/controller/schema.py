"""Checking request parameters against the interface's JSON-schema-like types, with messages naming the path.

The schemas are the small subset the generator writes (genom2bip/back/
interface.py): type, properties/required/additionalProperties, items with
min/maxItems, maxLength, enum, minimum/maximum, anyOf, min/maxProperties and
``{"$ref": name}`` into the interface's ``types``.
"""
from __future__ import annotations

import math
from itertools import islice
from typing import Any, Callable

_JSON_TYPES = {"object": "an object", "array": "an array", "string": "a string", "integer": "an integer",
               "number": "a number", "boolean": "a boolean (true or false)", "null": "null"}


#: The items of an array :func:`problems` looks at; the rest are not checked.
ITEMS_CHECKED = 10_000


def _resolved(schema: dict[str, Any], types: dict[str, dict[str, Any]]) -> dict[str, Any]:
    """``schema`` with its ``$ref`` followed to the named type (an unknown name: no constraint)."""
    while "$ref" in schema:
        schema = types.get(schema["$ref"], {})
    return schema


def _is(value: Any, kind: str) -> bool:
    if kind == "object":
        return isinstance(value, dict)
    if kind == "array":
        return isinstance(value, list)
    if kind == "string":
        return isinstance(value, str)
    if kind == "integer":
        return isinstance(value, int) and not isinstance(value, bool)
    if kind == "number":
        return isinstance(value, (int, float)) and not isinstance(value, bool)
    if kind == "boolean":
        return isinstance(value, bool)
    if kind == "null":
        return value is None
    return True


def _show(value: Any) -> str:
    text = repr(value) if not isinstance(value, (dict, list)) else type(value).__name__.replace("dict", "an object") \
        .replace("list", "an array")
    return text if len(text) <= 40 else text[:37] + "..."


def problems(value: Any, schema: dict[str, Any], types: dict[str, dict[str, Any]], path: str) -> list[str]:
    """What is wrong with ``value`` for ``schema`` (empty when nothing), each naming ``path``."""
    schema = _resolved(schema, types)
    if "anyOf" in schema:
        options = [problems(value, s, types, path) for s in schema["anyOf"]]
        return [] if any(not o for o in options) else options[0]
    kind = schema.get("type")
    if kind is not None and not _is(value, kind):
        return [f"{path}: expected {_JSON_TYPES.get(kind, kind)}, got {_show(value)}"]
    if kind in ("number", "integer") and isinstance(value, float) and not math.isfinite(value):
        return [f"{path}: {value} is not a finite number"]
    out: list[str] = []
    if "enum" in schema and value not in schema["enum"]:
        out.append(f"{path}: {_show(value)} is not one of {', '.join(map(str, schema['enum']))}")
    if kind in ("integer", "number"):
        if "minimum" in schema and value < schema["minimum"]:
            out.append(f"{path}: {value} is below the minimum {schema['minimum']}")
        if "maximum" in schema and value > schema["maximum"]:
            out.append(f"{path}: {value} is above the maximum {schema['maximum']}")
    if kind == "string" and "maxLength" in schema and len(value) > schema["maxLength"]:
        out.append(f"{path}: a string of at most {schema['maxLength']} characters expected, got {len(value)}")
    if kind == "array":
        if "minItems" in schema and len(value) < schema["minItems"]:
            out.append(f"{path}: at least {schema['minItems']} items expected, got {len(value)}")
        if "maxItems" in schema and len(value) > schema["maxItems"]:
            out.append(f"{path}: at most {schema['maxItems']} items expected, got {len(value)}")
        for i, item in enumerate(value[:ITEMS_CHECKED]):
            out += problems(item, schema.get("items", {}), types, f"{path}[{i}]")
            if len(out) > 20:
                break
    if kind == "object":
        props = schema.get("properties", {})
        for k, v in value.items():
            if k in props:
                out += problems(v, props[k], types, f"{path}.{k}")
            elif schema.get("additionalProperties") is False:
                out.append(f"{path}: unknown member {k!r} (members: {', '.join(props) or 'none'})")
        for k in schema.get("required", []):
            if k not in value:
                out.append(f"{path}: missing member {k!r}")
        if "maxProperties" in schema and len(value) > schema["maxProperties"]:
            out.append(f"{path}: one of {', '.join(props)} expected, got {len(value)} members")
        if "minProperties" in schema and len(value) < schema["minProperties"]:
            out.append(f"{path}: one of {', '.join(props)} expected")
    return out


def checker(schema: dict[str, Any], types: dict[str, dict[str, Any]]) -> Callable[[Any], bool]:
    """A test of values against ``schema``, made once: True only when :func:`problems` finds nothing, told without
    making a message (the check of every value a codel writes).  False says look closer (:func:`problems` has the
    last word), so its fast paths may be cautious."""
    return _test(schema, types, {})


def _test(schema: dict[str, Any], types: dict[str, dict[str, Any]], made: dict[int, Any]) -> Callable[[Any], bool]:
    """:func:`problems`' rules as one function of the value (``made``: the tests of the named types in progress, for a
    type that contains itself)."""
    schema = _resolved(schema, types)
    key = id(schema)
    if key in made:
        cell = made[key]
        return lambda v: cell[0](v)
    cell = made[key] = [None]
    cell[0] = test = _test_of(schema, types, made)
    return test


def _test_of(schema: dict[str, Any], types: dict[str, dict[str, Any]], made: dict[int, Any]) -> Callable[[Any], bool]:
    if "anyOf" in schema:
        options = [_test(s, types, made) for s in schema["anyOf"]]
        return lambda v: any(o(v) for o in options)
    kind = schema.get("type")
    enum = schema.get("enum")
    low, high = schema.get("minimum"), schema.get("maximum")
    if kind in ("integer", "number"):
        exact = (int,) if kind == "integer" else (int, float)
        if enum is None and low is None and high is None:
            if kind == "integer":
                return lambda v: type(v) is int
            return lambda v: type(v) is int or (type(v) is float and math.isfinite(v))
        return lambda v: type(v) in exact and (type(v) is int or math.isfinite(v)) and (enum is None or v in enum) \
            and (low is None or v >= low) and (high is None or v <= high)
    if kind == "array":
        items = schema.get("items", {})
        few, many = schema.get("minItems"), schema.get("maxItems")
        every = _all_of(items, types, made)
        return lambda v: type(v) is list and (few is None or len(v) >= few) and (many is None or len(v) <= many) \
            and (enum is None or v in enum) and every(v)
    if kind == "object":
        props = schema.get("properties", {})
        tests = {k: _test(t, types, made) for k, t in props.items()}
        closed = schema.get("additionalProperties") is False
        required = schema.get("required", [])
        most, least = schema.get("maxProperties"), schema.get("minProperties")

        def obj(v: Any) -> bool:
            if type(v) is not dict or (enum is not None and v not in enum):
                return False
            for k, x in v.items():
                t = tests.get(k)
                if t is None:
                    if closed:
                        return False
                elif not t(x):
                    return False
            return all(k in v for k in required) and (most is None or len(v) <= most) \
                and (least is None or len(v) >= least)
        return obj
    if kind == "string":
        longest = schema.get("maxLength")
        return lambda v: type(v) is str and (longest is None or len(v) <= longest) and (enum is None or v in enum)
    if kind == "boolean":
        return lambda v: type(v) is bool and (enum is None or v in enum)
    if kind == "null":
        return lambda v: v is None and (enum is None or v in enum)
    return lambda v: enum is None or v in enum  # no type, or one problems() reads nothing more of


def _all_of(items: dict[str, Any], types: dict[str, dict[str, Any]], made: dict[int, Any]) -> Callable[[list], bool]:
    """The test of an array's items (the first :data:`ITEMS_CHECKED`): a plain number or integer item type in one pass
    over the list in C, any other item by its test."""
    plain = _resolved(items, types)
    if "anyOf" not in plain and not ({"enum", "minimum", "maximum"} & plain.keys()) and \
            plain.get("type") in ("integer", "number"):
        allowed = {int} if plain["type"] == "integer" else {int, float}

        def numbers(v: list) -> bool:
            head = v if len(v) <= ITEMS_CHECKED else v[:ITEMS_CHECKED]
            if not set(map(type, head)) <= allowed:
                return False
            try:
                return float not in allowed or math.isfinite(math.fsum(head))
            except (OverflowError, ValueError):  # a sum past the largest float, or inf - inf: looked at closer
                return False
        return numbers
    one = _test(items, types, made)
    return lambda v: all(map(one, islice(v, ITEMS_CHECKED)))


def completed(value: Any, default: Any) -> Any:
    """``value`` with the members it leaves out taken from ``default`` (a partial struct keeps the other defaults)."""
    if isinstance(value, dict) and isinstance(default, dict):
        out = dict(default)
        for k, v in value.items():
            out[k] = completed(v, default.get(k))
        return out
    return value


def zero(schema: dict[str, Any], types: dict[str, dict[str, Any]]) -> Any:
    """The value of a variable of this type before anything is written (C's zero initialisation)."""
    schema = _resolved(schema, types)
    kind = schema.get("type")
    if "enum" in schema:
        return schema["enum"][0] if schema["enum"] else None
    if kind == "object" and "required" in schema and "maxProperties" not in schema:
        return {k: zero(v, types) for k, v in schema["properties"].items()}
    if kind == "array":
        return [zero(schema["items"], types) for _ in range(schema.get("minItems", 0))]
    return {"integer": 0, "number": 0.0, "boolean": False, "string": ""}.get(kind)
