"""GenoM3 ``.proba`` files: how often each codel went to each next state, as measured on the robot.

One line per transition, ``OWNER::COMPONENT_STATE::COMPONENT_NEXT N`` (the
format of Foughali's quadcopter artefact, ``all.proba``)::

    io::pom_read::pom_pause_read 1
    io::pom_read::pom_insert 9

``OWNER`` is the task or service whose automaton runs the codel, ``STATE``
the state that runs it, ``NEXT`` a state it yields (``pause_X`` is
``pause::X``, ``ether`` ends the activity), ``N`` a count or weight (not
negative).  The weights of one state's lines are its outcomes' relative
frequencies; an outcome of a listed state that has no line never happens
(its exceptions included); a state without lines chooses uniformly.  A
line of weight 0 for a yield the codel does not have (the artefact has
one, for a yield commented out of its ``.gen``) is a warning, and ignored.
Blank lines and lines starting with ``#`` are skipped.  Every problem is
reported at its file, line and column; nothing is simulated.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

from genom2bip import ir
from genom2bip.rules import _suggest
from runtime.diagnostics import Reporter, Span

_WORD = re.compile(r"\S+")
EXPECTED = "expected OWNER::COMPONENT_STATE::COMPONENT_NEXT N (e.g. io::pom_read::pom_insert 9)"


@dataclass
class Proba:
    """Weights of codel outcomes: ``(component, owner, state, outcome) -> weight`` (outcome as a yield prints:
    ``insert``, ``pause::read``, ``ether``)."""

    weights: dict[tuple[str, str, str, str], float] = field(default_factory=dict)
    path: str = ""


def _owners(description: ir.Description) -> dict[str, list[tuple[ir.Component, list[ir.Codel]]]]:
    """Each task or service name, with the components that have one of that name and its codels."""
    out: dict[str, list[tuple[ir.Component, list[ir.Codel]]]] = {}
    for c in description.components:
        for t in c.tasks:
            out.setdefault(t.name, []).append((c, list(t.codels)))
        for s in c.services:
            if s.codels:
                out.setdefault(s.name, []).append((c, s.fsm_codels()))
    return out


class _Reader:
    def __init__(self, path: str, description: ir.Description, reporter: Reporter) -> None:
        self.path, self.reporter = path, reporter
        self.owners = _owners(description)

    def error(self, line: int, column: int, width: int, message: str, hint: str | None = None) -> None:
        self.reporter.error(Span(self.path, line, column, line, column + width), message, hint)

    def read(self, text: str) -> Proba:
        out = Proba(path=self.path)
        seen: dict[tuple[str, str, str, str], int] = {}
        self.reporter.sources.add(self.path, text)
        for number, line in enumerate(text.splitlines(), 1):
            words = list(_WORD.finditer(line))
            if not words or words[0].group().startswith("#"):
                continue
            got = self.line(number, words)
            if got is None:
                continue
            key, weight, column = got
            if key in seen:
                self.error(number, column, len(words[0].group()), f"'{words[0].group()}' given twice "
                           f"(first on line {seen[key]})")
                continue
            seen[key] = number
            out.weights[key] = weight
        return out

    def line(self, number: int, words: list[re.Match]) -> tuple[tuple[str, str, str, str], float, int] | None:
        head = words[0]
        column = head.start() + 1
        parts = head.group().split("::")
        if len(parts) != 3 or not all(parts):
            self.error(number, column, len(head.group()), f"'{head.group()}' is not OWNER::STATE::NEXT", EXPECTED)
            return None
        if len(words) < 2:
            self.error(number, head.end() + 1, 1, "expected the number of occurrences after the transition", EXPECTED)
            return None
        if len(words) > 2:
            extra = words[2]
            self.error(number, extra.start() + 1, len(extra.group()),
                       f"unexpected '{extra.group()}' after the number of occurrences", EXPECTED)
            return None
        count = words[1]
        try:
            weight = float(count.group())
        except ValueError:
            weight = math.nan
        if not math.isfinite(weight) or weight < 0:
            self.error(number, count.start() + 1, len(count.group()),
                       f"'{count.group()}' is not a number of occurrences", "write a count, 0 or more (e.g. 9)")
            return None
        owner, state, nxt = parts
        state_col = column + len(owner) + 2
        next_col = state_col + len(state) + 2
        candidates = self.owners.get(owner)
        if not candidates:
            self.error(number, column, len(owner), f"no task or service is named '{owner}'",
                       _suggest(owner, sorted(self.owners)))
            return None
        for component, codels in candidates:
            prefix = component.name + "_"
            if not state.startswith(prefix):
                continue
            name = state[len(prefix):]
            codel = next((c for c in codels if name in c.triggers), None)
            if codel is None:
                continue
            outcome = self.outcome(nxt, prefix)
            yields = [str(y) for y in codel.yields]
            if outcome not in yields and weight == 0:  # a transition never seen, of another version of the codel
                self.reporter.warning(Span(self.path, number, next_col, number, next_col + len(nxt)),
                                      f"{component.name}.{owner}: state {name} (codel {codel.name}) does not yield "
                                      f"'{outcome}'; its weight is 0: line ignored")
                return None
            if outcome not in yields:
                self.error(number, next_col, len(nxt), f"{component.name}.{owner}: state {name} (codel {codel.name}) "
                           f"does not yield '{outcome}'",
                           f"it yields {', '.join(yields)}" if yields else f"codel {codel.name} yields nothing")
                return None
            return (component.name, owner, name, outcome), weight, column
        states = [f"{component.name}_{s}" for component, codels in candidates for s in ir.fsm_states(codels)]
        self.error(number, state_col, len(state), f"'{owner}' has no state '{state}'", _suggest(state, states))
        return None

    @staticmethod
    def outcome(word: str, prefix: str) -> str:
        """``pom_pause_read`` -> ``pause::read``, ``pom_insert`` -> ``insert`` (the component's prefix dropped)."""
        name = word[len(prefix):] if word.startswith(prefix) else word
        return f"pause::{name[len('pause_'):]}" if name.startswith("pause_") else name


def load_proba(path: Path, description: ir.Description, reporter: Reporter) -> Proba | None:
    """Read and check a ``.proba`` file against the description; problems go to ``reporter`` (None then)."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        reporter.error(Span(str(path), 0, 0), f"cannot read the .proba file: {getattr(exc, 'strerror', None) or exc}")
        return None
    out = _Reader(str(path), description, reporter).read(text)
    return None if reporter.has_errors else out
