"""A request's parameters: checked against the service's schemas when it arrives, stored and read back as GenoM does.

Inputs bound to ids members are written to the ids once the request is
accepted (GenoM attributes); outputs are read from the request's locals or
the ids when it finishes.
"""
from __future__ import annotations

from typing import Any

from runtime.controller.data import clone, get_path, path_steps, set_path
from runtime.controller.requests import Request, RequestError, Service
from runtime.controller.schema import completed, problems, zero


_KINDS = ((bool, "a boolean"), (str, "a string"), ((int, float), "a number"), (list, "an array"), (dict, "an object"))


def _kind(value: Any) -> tuple[type | tuple[type, ...], str] | None:
    return next(((t, name) for t, name in _KINDS if isinstance(value, t)), None)


def unsuited(held: Any, value: Any) -> str | None:
    """Why ``value`` may not replace ``held`` in the ids: another JSON kind (a number for a string...), else None.

    The schemas check inputs; this holds the ids to their kinds even where a
    schema says nothing (a package generated before member paths had one).
    """
    kind, new = _kind(held), _kind(value)
    if kind is None or new is None:
        return None
    if kind != new:
        return f"it holds {kind[1]}, not {new[1]} ({value!r})"
    if isinstance(held, int) and not isinstance(held, bool) and isinstance(value, float):
        return f"it holds an integer, not {value!r}"
    return None


def unstorable(root: dict[str, Any], member: str) -> str | None:
    """Why a value cannot be stored at the ids path ``member`` (None when it can)."""
    steps = path_steps(member)
    if not steps:
        return f"{member!r} is not a member path"
    target: Any = root
    where = ""
    for i, step in enumerate(steps):
        if isinstance(step, int):
            if not isinstance(target, list):
                return f"{where or 'the ids'} is not an array"
            if step >= len(target):
                return f"{where}[{step}] is out of range (length {len(target)})"
        elif not isinstance(target, dict):
            return f"{where or 'the ids'} is not a struct"
        elif step not in target and i < len(steps) - 1:
            return f"no member {step!r} in {where or 'the ids'}"
        where += f"[{step}]" if isinstance(step, int) else (f".{step}" if where else step)
        if i < len(steps) - 1:
            target = target[step]
    return None


def checked_inputs(svc: Service, inputs: Any, types: dict[str, Any], ids: dict[str, Any]) -> dict[str, Any]:
    """The inputs of a request to ``svc``, defaults filled in; :class:`RequestError` 422 names every problem."""
    if not isinstance(inputs, dict):
        raise RequestError(422, f"the parameters of {svc.label} must be a JSON object, not {type(inputs).__name__}")
    values, errors = inputs_of(svc.label, svc.spec, inputs, types, ids)
    if errors:
        raise RequestError(422, f"bad request to {svc.label}: " + "; ".join(errors))
    return values


def inputs_of(label: str, spec: dict[str, Any], inputs: Any, types: dict[str, Any],
              ids: dict[str, Any]) -> tuple[dict[str, Any], list[str]]:
    """The inputs of a request to the service ``label`` (its interface entry ``spec``), defaults filled in, and
    every problem with them; the one check of a request's inputs, which a mission's steps also get before a run."""
    if not isinstance(inputs, dict):
        return {}, [f"the parameters of {label} must be a JSON object, not {type(inputs).__name__}"]
    params = [p for p in spec["parameters"] if p["direction"] in ("in", "inout")]
    names = [p["name"] for p in params]
    errors = [f"unknown parameter {k!r} (parameters of {label}: {', '.join(names) or 'none'})"
              for k in inputs if k not in names]
    values: dict[str, Any] = {}
    for p in params:
        name = p["name"]
        if name in inputs:
            value = completed(inputs[name], p.get("default"))
            errors += problems(value, p["schema"], types, name)
            values[name] = value
        elif "default" in p:
            values[name] = clone(p["default"])
        else:
            errors.append(f"missing parameter {name!r}" + (f" ({p['doc']})" if p.get("doc") else ""))
    for p in params:
        if p["source"] == "ids" and p["name"] in values:
            member = p.get("member") or p["name"]
            problem = unstorable(ids, member) or unsuited(get_path(ids, path_steps(member)), values[p["name"]])
            if problem:
                errors.append(f"parameter {p['name']!r} cannot be stored in ids member "
                              f"{p.get('member') or p['name']}: {problem}")
    return values, errors


def request_locals(svc: Service, values: dict[str, Any], types: dict[str, Any]) -> dict[str, Any]:
    """What a request's codels see: the service's locals, then its parameters (the inputs, zero for the others)."""
    local = {n: clone(spec["initial"]) for n, spec in svc.spec["locals"].items()}
    for p in svc.spec["parameters"]:
        local[p["name"]] = clone(values[p["name"]]) if p["name"] in values else zero(p["schema"], types)
    return local


def store_inputs(svc: Service, req: Request, ids: dict[str, Any]) -> list[dict[str, Any]]:
    """Write the inputs bound to ids members to the ids; returns a failure for each input that has nowhere to go.

    :func:`checked_inputs` refuses such an input; should the ids have
    changed shape since, it is not lost without a word.
    """
    failures = []
    for p in svc.spec["parameters"]:
        if p["source"] == "ids" and p["direction"] in ("in", "inout") and p["name"] in req.locals:
            member = p.get("member") or p["name"]
            problem = unstorable(ids, member)
            if problem is None:
                set_path(ids, path_steps(member), clone(req.locals[p["name"]]))
                continue
            message = f"{req.label} request {req.id}: parameter {p['name']!r} not stored in ids member {member}: " \
                      f"{problem}"
            failures.append({"error": "bad input", "input": p["name"], "message": message})
    return failures


def outputs(svc: Service, req: Request, ids: dict[str, Any]) -> dict[str, Any]:
    """The outputs of a finished request: from its locals, or from the ids members they are bound to."""
    out = {}
    for p in svc.spec["parameters"]:
        if p["direction"] in ("out", "inout"):
            if p["source"] == "ids":
                out[p["name"]] = clone(get_path(ids, path_steps(p.get("member") or p["name"])))
            else:
                out[p["name"]] = clone(req.locals.get(p["name"]))
    return out
