"""Partial-order reduction where time cannot pass: of the steps enabled at such a state, take a persistent set.

Where time cannot pass, the steps that fire next all fire at the same instant, and those of independent parts of
the model (five tasks released at once, on two cores) commute: firing them in every order reaches the same
states by as many paths.  At such a state the search fires only a *stubborn set* of the enabled steps
(Valmari's), computed on the model's structure:

* the unit is a source of interactions (a connector, or a port alone), with the atoms it moves (``W``) and the
  atoms its enabling reads (``R``: its own, and those of every interaction that a priority puts above it,
  through chains of priorities, and the owners of the clocks its priorities' guards compare);
* two sources are dependent when one moves what the other reads;
* the set starts from what stops time (an atom in a place without a tick, or an enabled interaction that a
  priority puts above the tick): as long as none of its members fires, time stays stopped, so no delay can
  slip before it;
* an enabled member brings every source dependent on it; a disabled one the sources that can enable it
  (those moving the atom that lacks its port, or else every atom it reads);
* every check of the search (an observer, a response clock, the goal) sees its atoms moved in one order only:
  the sources that move them are made dependent on one another, so that the values a check reads come in
  the same sequence along every order the reduction keeps (what a visibility condition would otherwise
  require).

The search keeps the cycle condition: when a step of the set reaches a state already stored, the state's other
steps are fired too (the queue condition of breadth-first search, Bosnacki and Holzmann).  docs/verification/platform.md
(*Clock zones*) argues why verdicts, maxima and traces stay those of the full search.
"""
from __future__ import annotations

from dataclasses import dataclass

from runtime.engine.support import _matches, top_connectors
from runtime.zones.model import value


@dataclass
class SourceInfo:
    """What the reduction knows of one source of interactions."""

    atoms: frozenset[int]
    ports: tuple[tuple[int, str], ...]  # the (atom, port) leaves
    rendezvous: bool  # its only interaction takes every leaf: a leaf whose atom lacks its port disables it
    global_read: bool  # a priority with a discrete guard sits above it: it reads anything


class PartialOrder:
    """The static tables (per source: dependents, enablers) and the stubborn set of a state."""

    def __init__(self, z) -> None:
        self.z = z
        engine = z.space.engine
        self.n = len(engine.sources)
        flat = z.flat
        infos: list[SourceInfo] = []
        for src in engine.sources:
            if src.kind == "port":
                ports = ((src.port.atom, src.port.name),)
            else:
                ports = tuple((flat.ports[p].atom, flat.ports[p].name) for p in src.leaves)
            infos.append(SourceInfo(frozenset(a for a, _ in ports), ports,
                                    src.kind in ("port", "rendezvous") and not src.alternatives, False))
        self.info = infos
        self.high_of: list[int] = []  # per rule: its high side's sources and those above them (bitset)
        # which sources each original connector id reaches (ZoneExplorer.__init__'s tops, without the tick)
        tops: dict[int, set[int]] = {}
        for c, srcs in top_connectors(engine.sources).items():
            tops.setdefault(z.connector_id[c], set()).update(srcs)
        rules = z.model.rules
        low_of: list[set[int]] = [set() for _ in range(self.n)]  # rules where some interaction of s is low
        high_of: list[set[int]] = []  # per rule: the sources of its high side
        for r, rule in enumerate(rules):
            for cid, _ in rule.low:
                for s in tops.get(cid, ()):
                    low_of[s].add(r)
            high_of.append({s for cid, _ in rule.high for s in tops.get(cid, ())})
        clock_owner = {k + 1: atom for k, (atom, _) in enumerate(z.model.clocks)}
        natoms = len(flat.atoms)
        reads: list[set[int]] = []
        self.above = [0] * self.n  # the sources a priority puts above s, through chains (bitset)
        for s in range(self.n):
            above, todo, seen_rules = set(), [s], set()
            read = set(infos[s].atoms)
            while todo:
                t = todo.pop()
                for r in low_of[t] - seen_rules:
                    seen_rules.add(r)
                    guard = rules[r].guard
                    if guard is not None and not isinstance(guard, list):
                        infos[s].global_read = True
                    for d in guard or () if isinstance(guard, list) else ():
                        read |= {clock_owner.get(d.i, -1), clock_owner.get(d.j, -1)} - {-1}
                    for h in high_of[r] - above:
                        above.add(h)
                        todo.append(h)
                        read |= infos[h].atoms
            reads.append(read)
            for h in above:
                self.above[s] |= 1 << h
        for r in range(len(rules)):
            mask = 0
            for h in high_of[r]:
                mask |= 1 << h | self.above[h]
            self.high_of.append(mask)
        # the checks' atoms: each check is one more pseudo-atom, moved by every source moving one of its atoms
        checks: list[set[int]] = []
        for atom, (_, clock, _) in z.model.observers.items():
            checks.append({atom, clock_owner[clock]})
        for atom, (_, clock) in z.model.measures.items():
            checks.append({atom, clock_owner[clock]})
        if z.goal:
            offsets = {fa.offset: fa.index for fa in flat.atoms}
            checks.append({offsets[o] for group in z.goal for o, _ in group if o in offsets})
        moves: list[set[int]] = []
        for s in range(self.n):
            w = set(infos[s].atoms)
            w |= {natoms + c for c, atoms in enumerate(checks) if atoms & infos[s].atoms}
            moves.append(w)
            reads[s] |= w
        everything = set(range(natoms + len(checks)))
        for s in range(self.n):
            if infos[s].global_read:
                reads[s] = everything
        # bitsets over sources
        writers = [0] * (natoms + len(checks))
        for s in range(self.n):
            for a in moves[s]:
                writers[a] |= 1 << s
        self.writers = writers
        readers = [0] * (natoms + len(checks))
        for t in range(self.n):
            for a in reads[t]:
                readers[a] |= 1 << t
        self.own = [0] * self.n  # the sources moving one of its atoms (what can make its clock guard hold in zero time)
        for s in range(self.n):
            for a in infos[s].atoms:
                self.own[s] |= writers[a]
        self.enablers = [0] * self.n  # a disabled source whose leaves' atoms all offer their ports: all it reads
        self.dependents = [0] * self.n
        for s in range(self.n):
            mask = 0
            for a in reads[s]:
                mask |= writers[a]
            self.enablers[s] = mask
            for a in moves[s]:
                mask |= readers[a]
            self.dependents[s] = mask | 1 << s
        # the ports an atom offers from each place
        self.offers: dict[tuple[int, int], set[str]] = {}
        for fa in flat.atoms:
            for bit, place in enumerate(fa.places):
                self.offers[(fa.index, 1 << bit)] = {t.port for t in fa.type.transitions if place in t.sources}
        # the sources that take an atom out of a place: those with one of its ports offered there
        self.leaving: dict[tuple[int, int], int] = {}
        for (atom, bit), ports in self.offers.items():
            if None in ports or "" in ports:  # an internal transition leaves the place: any step of the atom
                self.leaving[(atom, bit)] = writers[atom]
                continue
            mask = 0
            for s, info in enumerate(infos):
                if any(a == atom and p in ports for a, p in info.ports):
                    mask |= 1 << s
            self.leaving[(atom, bit)] = mask
        tick = next(fc.id for fc in z.model.flat.connectors if fc.label == "tick")
        self.tick_rules = [r for r, rule in enumerate(rules) if any(c == tick for c, _ in rule.low)]
        self.stats = [0, 0, 0]  # nodes asked about, nodes given a smaller set, steps left out of those sets

    @staticmethod
    def _by_place(table: dict, atom: int, marking: int, empty):
        """The union of ``table[(atom, place bit)]`` over the places marked (an atom may mark several)."""
        got, bit = empty, 1
        while bit <= marking:
            if marking & bit:
                got = got | table.get((atom, bit), empty)
            bit <<= 1
        return got

    def _offers(self, atom: int, marking: int) -> set[str]:
        return self._by_place(self.offers, atom, marking, frozenset())

    def _leaving(self, atom: int, marking: int) -> int:
        return self._by_place(self.leaving, atom, marking, 0)

    def _enablers(self, s: int, state: tuple, stub: int) -> int:
        """Sources one of which must fire before disabled source ``s`` can: those taking an atom of it that lacks
        its port out of its place (the atom adding least to ``stub``), else all that move what it reads."""
        info = self.info[s]
        best = None
        if info.rendezvous:
            for atom, port in info.ports:
                marking = self.z.place_bit(state, atom)
                if port not in self._offers(atom, marking):
                    w = self._leaving(atom, marking)
                    if best is None or bin(w & ~stub).count("1") < bin(best & ~stub).count("1"):
                        best = w
        return self.enablers[s] if best is None else best

    def _witnesses(self, state: tuple, enabled: dict[int, list[int]]) -> list[int]:
        """Starting sets, as bitsets of sources: each keeps time stopped for as long as none of it fires."""
        z = self.z
        out = []
        for atom in z.model.timed_atoms:
            place = z.model.places[(atom, z.place_bit(state, atom))]
            fa = z.flat.atoms[atom]
            if not place.ticks or (place.discrete is not None and not value(place.discrete, fa, state)):
                out.append(self.writers[atom])
        blocks = z.blocking(state, sorted(i for ids in enabled.values() for i in ids))
        for r in self.tick_rules:
            if any(not b for b in blocks.region(r)):
                high = z.model.rules[r].high
                start = 0
                for s, ids in enabled.items():
                    if any(_matches(z.interaction(i)[0], high) for i in ids):
                        start |= 1 << s
                if start:
                    out.append(start)
        return out

    def ample(self, state: tuple, succ: list[tuple[int, tuple]], fires=None) -> set[int] | None:
        """The interactions to fire at ``state`` (where time cannot pass), or None for all of them.

        ``fires``, if given, says of an interaction whether it fires from the node's zone, and why not:
        ``"fires"``, ``"guard"`` (its clock guard fails there) or the set of rules each of which alone blocks it
        everywhere there (possibly empty).  A source whose clock guard fails can only be enabled, before time
        passes, by a step of its own atoms; one that a single rule blocks waits for that rule's high side to be
        disabled, so that side's enabled sources are enough as its enablers (the closure brings what disables
        them)."""
        self.stats[0] += 1
        enabled: dict[int, list[int]] = {}
        for i, _ in succ:
            enabled.setdefault(i % self.n, []).append(i)
        if len(enabled) < 2:
            return None
        on = 0
        for s in enabled:
            on |= 1 << s
        blocked: dict[int, list[int]] = {}  # source -> its possible sets of enablers, for those not firing here
        if fires is not None:
            for s, ids in enabled.items():
                why = [fires(i) for i in ids]
                if any(w == "fires" for w in why):
                    continue
                if all(w == "guard" for w in why):
                    blocked[s] = [self.own[s]]  # only its own atoms' steps can reset its clocks or change its guard
                else:
                    rules = set.intersection(*why) if all(w != "guard" for w in why) else set()  # one rule for all
                    blocked[s] = [self.high_of[r] & on for r in sorted(rules)] or [self.enablers[s]]
        best = on
        for start in self._witnesses(state, enabled):
            got = self._close(start, on, best, state, blocked)
            if got is not None and bin(got).count("1") < bin(best).count("1"):
                best = got
        if best == on:
            return None
        self.stats[1] += 1
        keep = {i for s, ids in enabled.items() if best >> s & 1 for i in ids}
        self.stats[2] += sum(len(ids) for s, ids in enabled.items() if not best >> s & 1)
        return keep

    def _close(self, start: int, on: int, best: int, state: tuple, blocked: dict[int, int]) -> int | None:
        """The stubborn set from ``start``, as its enabled sources; None once it is no better than ``best``."""
        limit = bin(best).count("1")
        stub, todo, done = start, start, 0
        while todo:
            low = todo & -todo
            s = low.bit_length() - 1
            todo &= ~low
            done |= low
            if s in blocked:
                options = blocked[s]
                stub |= min(options, key=lambda m: bin(m & ~stub).count("1"))
            else:
                stub |= self.dependents[s] if on & low else self._enablers(s, state, stub)
            if bin(stub & on).count("1") >= limit:
                return None
            todo = stub & ~done
        return stub & on
