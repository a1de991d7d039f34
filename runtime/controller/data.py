"""The data the BIP model leaves out: ids members, posters and port connections, as plain Python values.

Values are JSON-like Python data: dicts for structs, lists for sequences and
arrays, str for strings and enumerators, int/float/bool.  A poster holds its
last written value; it is replaced, never changed in place, so a reader in
another thread always sees one whole value.
"""
from __future__ import annotations

import re
import time
from dataclasses import dataclass
from typing import Any

_STEP = re.compile(r"\.?([A-Za-z_]\w*)|\[(\d+)\]")


#: The values :func:`clone` shares rather than copies (immutable).
_SCALARS = frozenset({int, float, str, bool, type(None)})


def clone(value: Any) -> Any:
    """A deep copy of JSON-like data (faster than copy.deepcopy for dicts, lists and scalars); a list of scalars alone
    (a scan, a path) is copied in one call."""
    if isinstance(value, dict):
        return {k: clone(v) for k, v in value.items()}
    if isinstance(value, list):
        if _SCALARS.issuperset(map(type, value)):
            return list(value)
        return [clone(v) for v in value]
    return value


def path_steps(path: str) -> list[str | int]:
    """``"pos.x"`` → ``["pos", "x"]``, ``"a[2].b"`` → ``["a", 2, "b"]``."""
    steps: list[str | int] = []
    for name, index in _STEP.findall(path):
        steps.append(name if name else int(index))
    return steps


def get_path(root: dict[str, Any], steps: list[str | int]) -> Any:
    value: Any = root
    for s in steps:
        try:
            value = value[s]
        except (KeyError, IndexError, TypeError):
            return None
    return value


def set_path(root: dict[str, Any], steps: list[str | int], value: Any) -> None:
    target: Any = root
    for s in steps[:-1]:
        target = target[s]
    target[steps[-1]] = value


def resolve(schema: dict[str, Any], types: dict[str, dict[str, Any]]) -> dict[str, Any]:
    """The schema a ``{"$ref": name}`` stands for."""
    while "$ref" in schema:
        schema = types.get(schema["$ref"], {})
    return schema


@dataclass(frozen=True)
class PosterValue:
    """One written value of a poster: ``seq`` counts the writes (0: never written), ``time`` is when (monotonic s)."""

    component: str
    port: str
    value: Any
    seq: int
    time: float | None

    def as_json(self) -> dict[str, Any]:
        return {"component": self.component, "port": self.port, "value": self.value, "seq": self.seq,
                "written": self.seq > 0}


class Data:
    """ids members of every component, its posters (port out) and where each port in reads from.

    A ``port in P`` reads, by default, the only ``port out`` named ``P`` of
    another component (``NDD.Obs`` reads ``Aspect.Obs``); :meth:`connect`
    changes that.
    """

    def __init__(self, interface: dict[str, Any]) -> None:
        self.types: dict[str, dict[str, Any]] = interface.get("types", {})
        comps = interface["components"]
        self.ids: dict[str, dict[str, Any]] = {
            c: {name: clone(m["initial"]) for name, m in spec["ids"].items()} for c, spec in comps.items()}
        self.posters: dict[tuple[str, str], PosterValue] = {}
        # why a poster is no longer written: the failure of the codel that writes it, until its next write
        self.failures: dict[tuple[str, str], dict[str, Any]] = {}
        self.inputs: dict[tuple[str, str], tuple[str, str] | None] = {}
        outs: dict[str, list[str]] = {}
        for c, spec in comps.items():
            for p, port in spec["ports"].items():
                if port["direction"] == "out":
                    self.posters[(c, p)] = PosterValue(c, p, None, 0, None)
                    outs.setdefault(p, []).append(c)
        for c, spec in comps.items():
            for p, port in spec["ports"].items():
                if port["direction"] == "in":
                    writers = [w for w in outs.get(p, []) if w != c]
                    self.inputs[(c, p)] = (writers[0], p) if len(writers) == 1 else None

    def connect(self, component: str, port: str, target: str) -> None:
        """Make ``component``'s ``port in port`` read the poster ``target`` (``"Aspect.Obs"``)."""
        if (component, port) not in self.inputs:
            raise KeyError(f"{component} has no port in named {port!r}")
        tc, _, tp = target.partition(".")
        if (tc, tp) not in self.posters:
            raise KeyError(f"no poster {target!r} (posters: {', '.join(f'{a}.{b}' for a, b in self.posters)})")
        self.inputs[(component, port)] = (tc, tp)

    def read_input(self, component: str, port: str) -> Any:
        """What a ``port in`` sees: a copy of the connected poster's last value, None if never written."""
        src = self.inputs.get((component, port))
        if src is None:
            return None
        return clone(self.posters[src].value)

    def poster(self, component: str, port: str) -> PosterValue:
        return self.posters[(component, port)]

    def write_poster(self, component: str, port: str, value: Any) -> PosterValue:
        old = self.posters[(component, port)]
        new = PosterValue(component, port, clone(value), old.seq + 1, time.monotonic())
        self.posters[(component, port)] = new
        self.failures.pop((component, port), None)
        return new

    def stale(self, component: str, ports: list[str], who: dict[str, Any]) -> list[str]:
        """Mark the posters ``ports`` as no longer written, for the failure ``who``; their names."""
        for port in ports:
            if (component, port) in self.posters:
                self.failures[(component, port)] = dict(who)
        return [f"{component}.{port}" for port in ports if (component, port) in self.posters]

    def poster_view(self, component: str, port: str) -> dict[str, Any]:
        """A poster as a client sees it: its value, how old it is, and why it is no longer written, if it is not."""
        value = self.posters[(component, port)]
        age = round((time.monotonic() - value.time) * 1e3, 1) if value.time is not None else None
        return value.as_json() | {"age_ms": age, "failure": self.failures.get((component, port))}
