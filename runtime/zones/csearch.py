"""The zone graph search run in C (zsearch.c): the same search as ZoneExplorer's Python loop, node for node.

The C search keeps the passed/waiting store and does every zone operation; it asks Python once per discrete
state for that state's *program* (ZoneExplorer.program: successors with their guards, resets and blocked
regions, where time may pass, idle clocks, watched clocks), the only part that reads the BIP model.  When the
search ends, its nodes and steps become the explorer's ``nodes`` and ``out`` for traces and lassos.
"""
from __future__ import annotations

import ctypes
from functools import cache
from pathlib import Path

import numpy as np

HERE = Path(__file__).parent
PROGRAM = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_int64)
PROGRESS = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_int64, ctypes.c_int64, ctypes.c_int64, ctypes.c_int64,
                            ctypes.c_int64)
#: zs_run's statuses.
STOPPED = {0: "", 1: "max-states", 2: "violated", 3: "interrupted"}


@cache
def library():
    """zsearch.c (with dbm.c in front) compiled and loaded, or None without a compiler."""
    from runtime.native.build import BuildError, build, compiler

    cc = compiler()
    if cc is None:
        return None
    source = (HERE / "dbm.c").read_text() + "\n" + (HERE / "zsearch.c").read_text()
    try:
        lib = ctypes.CDLL(str(build(source, cc, what="zone search")), mode=ctypes.RTLD_LOCAL)
    except (BuildError, OSError):
        return None
    p, i32, i64, dbl = ctypes.c_void_p, ctypes.c_int, ctypes.c_int64, ctypes.POINTER(ctypes.c_double)
    for name, res, args in (
            ("zs_new", p, [i32, dbl, i32, i32, i32]), ("zs_free", None, [p]),
            ("zs_set_program", i32, [p, i64, ctypes.POINTER(i64), i64]),
            ("zs_initial", i32, [p, i64, dbl, PROGRAM]),
            ("zs_run", i32, [p, i64, i32, PROGRAM, PROGRESS, i64]),
            ("zs_counts", None, [p, ctypes.POINTER(i64)]), ("zs_nodes", None, [p, i32, ctypes.POINTER(i64)]),
            ("zs_edges", None, [p, ctypes.POINTER(ctypes.c_int32)]),
            ("zs_members", None, [p, ctypes.POINTER(ctypes.c_int32)]),
            ("zs_guards", None, [p, ctypes.POINTER(i64)]), ("zs_zone", None, [p, i64, dbl]),
            ("zs_results", None, [p, ctypes.POINTER(ctypes.c_int32), dbl, ctypes.POINTER(ctypes.c_int32)])):
        fn = getattr(lib, name)
        fn.restype, fn.argtypes = res, args
    return lib


def _dbl(a: np.ndarray):
    return a.ctypes.data_as(ctypes.POINTER(ctypes.c_double))


class CSearch:
    """One C search over a ZoneExplorer's model; ``run`` fills the explorer's nodes and result."""

    def __init__(self, z, lib) -> None:
        self.z, self.lib = z, lib
        self.d = z.n + 1
        self.observers = {atom: slot for slot, atom in enumerate(z.model.observers)}
        ceiling = np.ascontiguousarray(z.ceiling, dtype=np.float64)
        self.ctx = lib.zs_new(self.d, _dbl(ceiling), len(self.observers), z.n, int(z.merge))
        if not self.ctx:
            raise MemoryError("zone search: no memory for its context")
        self.error: BaseException | None = None
        self._program = PROGRAM(self._ask)

    def __del__(self) -> None:
        if getattr(self, "ctx", None):
            self.lib.zs_free(self.ctx)
            self.ctx = None

    def _ask(self, state_id: int) -> int:
        """The program callback: never lets an exception into C (it is raised when the search returns)."""
        try:
            words = np.asarray(self.z.program(self.z.states[state_id], self.observers), dtype=np.int64)
            return self.lib.zs_set_program(self.ctx, state_id, words.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)),
                                           len(words))
        except BaseException as e:  # noqa: BLE001 - re-raised by run()
            self.error = e
            return 1

    def run(self, result, max_states: int | None, progress, stop_at_violation: bool):
        from runtime.zones.model import Unsupported

        z, lib = self.z, self.lib

        def tick(nodes, transitions, waiting, memory, _depth) -> int:
            try:
                progress.tick(nodes, transitions, waiting, lambda: memory)
            except KeyboardInterrupt:
                return 1
            return 0

        callback = PROGRESS(tick)
        for sid in z.space.initial_ids:
            state = z.space.state(sid)
            zone = z.initial_zone()
            status = lib.zs_initial(self.ctx, z.state_id(state), _dbl(zone), self._program)
            self._raise(status, Unsupported)
        status = lib.zs_run(self.ctx, -1 if max_states is None else max_states, int(stop_at_violation),
                            self._program, callback, 64)
        self._raise(status, Unsupported)
        counts = (ctypes.c_int64 * 12)()
        lib.zs_counts(self.ctx, counts)
        result.states, result.discrete, result.transitions, result.merged = counts[0], counts[1], counts[2], counts[3]
        z.dropped = counts[4]
        if status:
            result.complete, result.stopped = False, STOPPED[status]
        self._nodes(counts)
        violation = (ctypes.c_int32 * max(1, len(self.observers)))()
        top, node = np.zeros(self.d), (ctypes.c_int32 * self.d)()
        lib.zs_results(self.ctx, violation, _dbl(top), node)
        for atom, slot in self.observers.items():
            if violation[slot] >= 0:
                result.violations[atom] = violation[slot]
        for clock in range(1, self.d):
            if node[clock] >= 0:
                result.maxima[clock] = (float(top[clock]), node[clock])
        return result

    def _raise(self, status: int, unsupported) -> None:
        if status == -1:
            error, self.error = self.error, None
            raise error
        if status == -2:
            counts = (ctypes.c_int64 * 12)()
            self.lib.zs_counts(self.ctx, counts)
            raise unsupported(f"priority {self.z.model.rules[counts[10]].name}: time waits for a clock condition "
                              "that is not one lower bound")
        if status == -9:
            raise MemoryError("zone search: out of memory")

    def _nodes(self, counts) -> None:
        """The C search's nodes, steps into covered zones and edges as the explorer's ``nodes`` and ``out``."""
        from runtime.zones.search import Node

        z, lib = self.z, self.lib
        n_nodes, n_steps, n_edges, n_members, n_guards = counts[0], counts[5], counts[6], counts[7], counts[8]
        guards = np.zeros(max(1, n_guards), dtype=np.int64)
        lib.zs_guards(self.ctx, guards.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)))
        members = np.zeros((max(1, n_members), 2), dtype=np.int32)
        lib.zs_members(self.ctx, members.ctypes.data_as(ctypes.POINTER(ctypes.c_int32)))
        zone = np.zeros((self.d, self.d))

        def load(slot: int):
            lib.zs_zone(self.ctx, slot, _dbl(zone))
            return zone.astype(np.float32)

        def make(rows: np.ndarray) -> list:
            out = []
            for state, parent, via, by, slot, own, first, goff, glen, flags in rows.tolist():
                g = guards[goff:goff + 3 * glen].tolist()
                n = Node(z.states[state], None, parent, via, list(zip(g[0::3], g[1::3], g[2::3])), bool(flags & 1))
                n._zone = load(slot) if slot >= 0 else None
                n.covered, n.expanded, n.by = bool(flags & 2), bool(flags & 4), by
                if own >= 0:
                    n._own = load(own)
                while first >= 0:
                    n.members.append(int(members[first, 0]))
                    first = int(members[first, 1])
                out.append(n)
            return out

        rows = np.zeros((max(1, n_nodes), 10), dtype=np.int64)
        lib.zs_nodes(self.ctx, 0, rows.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)))
        z.nodes = make(rows[:n_nodes])
        srows = np.zeros((max(1, n_steps), 10), dtype=np.int64)
        lib.zs_nodes(self.ctx, 1, srows.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)))
        steps = make(srows[:n_steps])
        edges = np.zeros((max(1, n_edges), 3), dtype=np.int32)
        lib.zs_edges(self.ctx, edges.ctypes.data_as(ctypes.POINTER(ctypes.c_int32)))
        z.out = [[] for _ in range(n_nodes)]
        for frm, target, ref in edges[:n_edges].tolist():
            z.out[frm].append((target, z.nodes[ref] if ref >= 0 else steps[-ref - 1]))
