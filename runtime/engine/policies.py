"""Choice policies: which enabled interaction a run fires. Any callable ``(state, enabled) -> Interaction | None``.

Returning None ends the run cleanly (outcome ``stopped``).
"""
from __future__ import annotations

import random
import sys
from typing import Callable, TextIO

from runtime.engine.interaction import Interaction


def first(state, enabled: list[Interaction]) -> Interaction:
    """The first enabled interaction, in the engine's fixed order (connectors as declared, then lone ports)."""
    return enabled[0]


class RandomPolicy:
    """Uniform choice among the enabled interactions, reproducible from a seed."""

    def __init__(self, seed: int | None = None) -> None:
        self.seed = seed
        self.rng = random.Random(seed)

    def __call__(self, state, enabled: list[Interaction]) -> Interaction:
        return enabled[self.rng.randrange(len(enabled))]


class InteractivePolicy:
    """Lists the enabled interactions by number on a terminal and reads the choice.

    ``s`` prints the state, ``q`` or end of input stops the run; an empty line
    takes the first interaction.
    """

    def __init__(self, describe: Callable[[tuple], str] | None = None, stdin: TextIO | None = None,
                 stdout: TextIO | None = None) -> None:
        self.describe = describe
        self.stdin = stdin or sys.stdin
        self.stdout = stdout or sys.stdout

    def __call__(self, state, enabled: list[Interaction]) -> Interaction | None:
        out = self.stdout
        for k, inter in enumerate(enabled, 1):
            print(f"  [{k}] {inter.label}", file=out)
        while True:
            print(f"choose 1-{len(enabled)} (s: state, q: quit)> ", end="", file=out, flush=True)
            line = self.stdin.readline()
            if not line:
                print(file=out)
                return None
            text = line.strip()
            if text == "":
                return enabled[0]
            if text in ("q", "quit"):
                return None
            if text in ("s", "state"):
                print(self.describe(state) if self.describe else repr(state), file=out)
                continue
            if text.isdigit() and 1 <= int(text) <= len(enabled):
                return enabled[int(text) - 1]
            print(f"  not a choice: {text!r}", file=out)


def make_policy(name: str, seed: int | None = None, describe=None) -> Callable:
    """The policy a command line names: ``first``, ``random`` or ``interactive``."""
    if name == "first":
        return first
    if name == "random":
        return RandomPolicy(seed)
    if name == "interactive":
        return InteractivePolicy(describe)
    raise ValueError(f"unknown policy '{name}' (first, random, interactive)")
