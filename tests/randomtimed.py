"""Random small networks of timed automata, written in TChecker's format, and an oracle for them: their integer-time
semantics explored state by state, written here from the format's documented meaning, independent of the zone
engine and of the translation to BIP (runtime/tchecker/translate.py).

For closed timed automata (every clock constraint non-strict, integer constants) the locations reachable in dense
time are those reachable with integer delays (Henzinger, Manna, Pnueli, 1992).  Strict constraints are read on a
time grid of ``1/grid`` as the reader does (``x < c`` as ``x <= c - 1/grid``), which makes the automaton closed on
that grid: the oracle ticks by ``1/grid`` and compares the same scaled constants.
"""
from __future__ import annotations

import random
from dataclasses import dataclass, field

#: The integer variable's domain: an edge whose assignment leaves it is not taken.
LOW, HIGH = 0, 2
OPS = ("<=", ">=", "==", "<", ">")


@dataclass
class Edge:
    process: int
    source: int
    target: int
    event: str
    guard: tuple[str, int] | None = None  # the process's clock compared with a constant
    test: tuple[str, int] | None = None  # the integer compared with a constant
    reset: int | None = None  # the clock's new value
    assign: int | None = None  # the integer's new value


@dataclass
class Location:
    kind: str = ""  # "", "urgent" or "committed"
    invariant: tuple[str, int] | None = None  # ("<=" or "<", c)


@dataclass
class Network:
    locations: list[list[Location]]  # per process
    edges: list[Edge]
    syncs: list[list[tuple[int, str]]] = field(default_factory=list)  # strong sync vectors: (process, event)

    def text(self) -> str:
        out = ["system:random", "event:a", "event:b", "event:c", f"int:1:{LOW}:{HIGH}:0:n"]
        for p, locs in enumerate(self.locations):
            out += [f"process:P{p}", f"clock:1:x{p}"]
            for k, loc in enumerate(locs):
                attrs = (["initial:"] if k == 0 else []) + ([f"{loc.kind}:"] if loc.kind else [])
                if loc.invariant:
                    attrs.append(f"invariant: x{p} {loc.invariant[0]} {loc.invariant[1]}")
                attrs.append(f"labels: L{p}_{k}")
                out.append(f"location:P{p}:l{k}{{{' : '.join(attrs)}}}")
        for e in self.edges:
            guard = ([f"x{e.process} {e.guard[0]} {e.guard[1]}"] if e.guard else []) + \
                ([f"n {e.test[0]} {e.test[1]}"] if e.test else [])
            stmts = ([f"x{e.process} = {e.reset}"] if e.reset is not None else []) + \
                ([f"n = {e.assign}"] if e.assign is not None else [])
            attrs = ([f"provided: {' && '.join(guard)}"] if guard else []) + ([f"do: {'; '.join(stmts)}"] if stmts
                                                                             else [])
            out.append(f"edge:P{e.process}:l{e.source}:l{e.target}:{e.event}" +
                       (f"{{{' : '.join(attrs)}}}" if attrs else ""))
        out += ["sync:" + ":".join(f"P{p}@{ev}" for p, ev in sync) for sync in self.syncs]
        return "\n".join(out) + "\n"

    @property
    def strict(self) -> bool:
        return any(b and b[0] in ("<", ">") for b in [e.guard for e in self.edges] +
                   [loc.invariant for locs in self.locations for loc in locs])


def network(rng: random.Random) -> Network:
    """One to three processes of two to four locations, one clock each, over one shared integer."""
    locations, edges = [], []
    for p in range(rng.randint(1, 3)):
        locs = []
        for k in range(rng.randint(2, 4)):
            r = rng.random()
            kind = "committed" if k and r < 0.2 else "urgent" if k and r < 0.32 else ""
            invariant = None
            if not kind and rng.random() < 0.4:
                invariant = ("<", rng.randint(1, 3)) if rng.random() < 0.25 else ("<=", rng.randint(0, 3))
            locs.append(Location(kind, invariant))
        locations.append(locs)
        for _ in range(rng.randint(1, 5)):
            edges.append(Edge(
                p, rng.randrange(len(locs)), rng.randrange(len(locs)), rng.choice("abc"),
                guard=(rng.choice(OPS), rng.randint(0, 3)) if rng.random() < 0.6 else None,
                test=(rng.choice(["==", "!=", "<", ">="]), rng.randint(0, 2)) if rng.random() < 0.35 else None,
                reset=rng.randint(0, 1) if rng.random() < 0.5 else None,
                assign=rng.randint(LOW - 1, HIGH) if rng.random() < 0.35 else None))
    syncs = []
    if len(locations) >= 2 and rng.random() < 0.6:
        parts = rng.sample(range(len(locations)), rng.randint(2, len(locations)))
        syncs.append([(p, rng.choice("abc")) for p in parts])
    return Network(locations, edges, syncs)


def _holds(value: int, op: str, bound: int) -> bool:
    return {"<=": value <= bound, ">=": value >= bound, "==": value == bound, "<": value < bound,
            ">": value > bound, "!=": value != bound}[op]


def _scaled(op: str, c: int, grid: int) -> tuple[str, int]:
    """A clock constraint on the grid: ``x < c`` is ``x <= grid*c - 1``, ``x > c`` is ``x >= grid*c + 1``."""
    return {"<": ("<=", grid * c - 1), ">": (">=", grid * c + 1)}.get(op, (op, grid * c))


def configurations(net: Network, grid: int) -> set[tuple[tuple[str, ...], int]]:
    """Every reachable (locations, integer) pair, by ticks of ``1/grid``: what the zone engine must find too."""
    n = len(net.locations)
    cap = grid * 4 + 1  # above every scaled constant (constants are at most 3): clocks past it are all alike
    synced = {(p, ev) for sync in net.syncs for p, ev in sync}
    moves: list[list[Edge]] = [[e] for e in net.edges if (e.process, e.event) not in synced]
    for sync in net.syncs:
        choices = [[e for e in net.edges if e.process == p and e.event == ev] for p, ev in sync]
        moves += _product(choices)

    def step(state, move):
        locs, clocks, value = state
        if any(locs[e.process] != e.source for e in move):
            return None
        committed = any(net.locations[p][locs[p]].kind == "committed" for p in range(n))
        if committed and not any(net.locations[e.process][e.source].kind == "committed" for e in move):
            return None
        for e in move:
            if e.guard and not _holds(clocks[e.process], *_scaled(*e.guard, grid)):
                return None
            if e.test and not _holds(value, *e.test):
                return None
        locs, clocks = list(locs), list(clocks)
        for e in move:  # statements in the order the move lists its edges
            if e.assign is not None:
                value = e.assign
            if e.reset is not None:
                clocks[e.process] = e.reset * grid
            locs[e.process] = e.target
        if not LOW <= value <= HIGH:
            return None
        if not _invariants(net, locs, clocks, grid):
            return None
        return tuple(locs), tuple(clocks), value

    def tick(state):
        locs, clocks, value = state
        if any(net.locations[p][locs[p]].kind for p in range(n)):
            return None
        later = tuple(min(c + 1, cap) for c in clocks)
        return (locs, later, value) if _invariants(net, locs, later, grid) else None

    start = (tuple([0] * n), tuple([0] * n), 0)
    seen, todo = {start}, [start]
    while todo:
        state = todo.pop()
        for nxt in [step(state, m) for m in moves] + [tick(state)]:
            if nxt is not None and nxt not in seen:
                seen.add(nxt)
                todo.append(nxt)
    return {(tuple(f"l{k}" for k in locs), value) for locs, _, value in seen}


def _invariants(net: Network, locs, clocks, grid: int) -> bool:
    for p, k in enumerate(locs):
        inv = net.locations[p][k].invariant
        if inv and not _holds(clocks[p], *_scaled(*inv, grid)):
            return False
    return True


def _product(choices: list[list[Edge]]) -> list[list[Edge]]:
    out: list[list[Edge]] = [[]]
    for options in choices:
        out = [done + [e] for done in out for e in options]
    return out
