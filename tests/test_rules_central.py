"""Connectors between local controllers accept exactly the request sequences a central controller (R2C) accepts.

For the same rules, the model genom2bip synthesises and a model where one
central atom checks every rule are explored exhaustively; their traces,
projected on the request and report interactions, must be the same sets
(checked by determinising both projections together).
"""
from __future__ import annotations

import re
import textwrap
from collections import deque
from pathlib import Path

import pytest

from central_controller import CentralLevel
from genom2bip.build.functional import FunctionalLevel
from genom2bip.parser import parse_paths
from genom2bip.rules import all_rules
from runtime.diagnostics import Reporter
from runtime.explore import StateSpace, explore

PAIR = Path(__file__).parent / "fixtures" / "rules" / "pair.gen"
OBSERVED = re.compile(r":(trigger|refuse|reject|finish|fail|interrupted)$")

RULE_SETS = {
    "requires-once-and-running": """\
        - id: localised
          service: Arm.Move
          requires: [Base.Localise]
        - id: tracking
          service: Arm.Move
          requires_running: [Base.Track]
          on_violation: wait
        """,
    "requires-latest-and-forbidden": """\
        - id: last-fix-good
          service: Arm.Move
          requires: [Base.Localise]
          completed: latest
        - id: no-park-while-tracking
          service: Arm.Park
          forbidden_while: [Base.Track]
        """,
    "exclusive-and-interrupts": """\
        - id: one-mover
          exclusive: [Arm.Move, Base.Track]
          on_violation: wait
        - id: park-halts-tracking
          service: Arm.Park
          interrupts: [Base.Track]
        """,
}


def projected(space: StateSpace) -> dict[int, list[tuple[str | None, int]]]:
    """Every state's moves, labels outside the request/report interactions hidden (None)."""
    explore(space)
    out = {}
    for sid in range(len(space)):
        edges = space.successors(sid)
        moves = []
        for k in range(0, len(edges), 2):
            label = space.labels[edges[k]]
            moves.append((label if OBSERVED.search(label) else None, edges[k + 1]))
        out[sid] = moves
    return out


def closure(lts, states) -> frozenset[int]:
    seen, todo = set(states), list(states)
    while todo:
        for label, t in lts[todo.pop()]:
            if label is None and t not in seen:
                seen.add(t)
                todo.append(t)
    return frozenset(seen)


def after(lts, states) -> dict[str, frozenset[int]]:
    out: dict[str, set[int]] = {}
    for s in states:
        for label, t in lts[s]:
            if label is not None:
                out.setdefault(label, set()).add(t)
    return {label: closure(lts, ts) for label, ts in out.items()}


def trace_difference(a, b) -> list[str] | None:
    """A shortest observable trace one LTS has and the other not; None when their trace sets are equal."""
    start = (closure(a, [0]), closure(b, [0]))
    parent = {start: None}
    todo = deque([start])
    while todo:
        pair = todo.popleft()
        moves_a, moves_b = after(a, pair[0]), after(b, pair[1])
        for label in sorted(set(moves_a) | set(moves_b)):
            if label not in moves_a or label not in moves_b:
                trace = [label]
                node = pair
                while parent[node] is not None:
                    node, step = parent[node]
                    trace.append(step)
                return trace[::-1]
            nxt = (moves_a[label], moves_b[label])
            if nxt not in parent:
                parent[nxt] = (pair, label)
                todo.append(nxt)
    return None


def models(tmp_path, rules_text: str):
    description = parse_paths([PAIR])
    path = tmp_path / "rules.yaml"
    path.write_text("rules:\n" + textwrap.indent(textwrap.dedent(rules_text), "  "))
    reporter = Reporter()
    rules = all_rules(description, path, reporter)
    assert not reporter.has_errors, [d.message for d in reporter.diagnostics]
    return description, rules


@pytest.mark.parametrize("name", sorted(RULE_SETS))
def test_synthesised_connectors_accept_what_a_central_controller_accepts(tmp_path, name):
    description, rules = models(tmp_path, RULE_SETS[name])
    local = projected(StateSpace(FunctionalLevel(description, "pair", rules).build(), "PAIR()", keep_edges=True))
    central = projected(StateSpace(CentralLevel(description, "pair", rules).build(), "PAIR()", keep_edges=True))
    assert len(local) > 1000 and len(central) > 1000  # a real exploration, not a trivial one
    assert trace_difference(local, central) is None


def test_a_central_controller_that_forgets_a_rule_is_told_apart(tmp_path):
    description, rules = models(tmp_path, RULE_SETS["requires-once-and-running"])
    forgetful = [r for r in rules if r.id != "tracking"]
    local = projected(StateSpace(FunctionalLevel(description, "pair", rules).build(), "PAIR()", keep_edges=True))
    central = projected(StateSpace(CentralLevel(description, "pair", forgetful).build(), "PAIR()",
                                   keep_edges=True))
    trace = trace_difference(local, central)
    assert trace is not None and trace[-1] == "Arm.Move:trigger"
    assert "Base.Track:trigger" not in trace  # accepted while Base.Track never ran: only the forgetful one allows it

