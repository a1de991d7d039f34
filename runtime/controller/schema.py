"""Checking request parameters against the interface's JSON-schema-like types, with messages naming the path.

The schemas are the small subset the generator writes (genom2bip/back/
interface.py): type, properties/required/additionalProperties, items with
min/maxItems, maxLength, enum, minimum/maximum, anyOf, min/maxProperties and
``{"$ref": name}`` into the interface's ``types``.
"""
from __future__ import annotations

import math
from typing import Any

_JSON_TYPES = {"object": "an object", "array": "an array", "string": "a string", "integer": "an integer",
               "number": "a number", "boolean": "a boolean (true or false)", "null": "null"}


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
    while "$ref" in schema:
        schema = types.get(schema["$ref"], {})
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
        for i, item in enumerate(value[:10_000]):
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
    while "$ref" in schema:
        schema = types.get(schema["$ref"], {})
    kind = schema.get("type")
    if "enum" in schema:
        return schema["enum"][0] if schema["enum"] else None
    if kind == "object" and "required" in schema and "maxProperties" not in schema:
        return {k: zero(v, types) for k, v in schema["properties"].items()}
    if kind == "array":
        return [zero(schema["items"], types) for _ in range(schema.get("minItems", 0))]
    return {"integer": 0, "number": 0.0, "boolean": False, "string": ""}.get(kind)
