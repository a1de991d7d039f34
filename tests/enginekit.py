"""Helpers shared by the engine tests: load fixture models, fire by label, list labels."""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path

from runtime.bip2 import parse_file
from runtime.engine import Engine

FIXTURES = Path(__file__).parent / "fixtures" / "engine"


@lru_cache(maxsize=None)
def package(name: str):
    return parse_file(FIXTURES / f"{name}.bip")


def engine(name: str, root: str = "System()", externs=None) -> Engine:
    return Engine(package(name), root, externs)


def labels(e: Engine, state) -> list[str]:
    return [i.label for i in e.enabled(state)]


def walk(e: Engine, *steps: str, state=None):
    """Fire the interactions with these labels in turn, from ``state`` or the initial state."""
    s = e.initial_state() if state is None else state
    for label in steps:
        s = e.fire(s, e.find(s, label))
    return s


def atom(e: Engine, state, name: str) -> dict:
    return e.describe_state(state)[name]
