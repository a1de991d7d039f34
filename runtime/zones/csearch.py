"""The zone graph search run in C (zsearch.c): the same search as ZoneExplorer's Python loop, node for node.

The C search keeps the passed/waiting store and does every zone operation; it asks Python once per discrete
state for that state's *program* (ZoneExplorer.program: successors with their guards, resets and blocked
regions, where time may pass, idle clocks, watched clocks), the only part that reads the BIP model.  When the
search ends, its nodes and steps become the explorer's ``nodes`` and ``out`` for traces and lassos.
"""
from __future__ import annotations

import ctypes
from functools import cache, cached_property
from pathlib import Path

import numpy as np

from runtime.zones.node import GOAL, Node, _double

HERE = Path(__file__).parent
PROGRAM = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_int64)  # also the interaction callback
AMPLE = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_int64, ctypes.c_int64)  # a node's state and zone slot
PROGRESS = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_int64, ctypes.c_int64, ctypes.c_int64, ctypes.c_int64,
                            ctypes.c_int64)
#: zs_run's statuses.
STOPPED = {0: "", 1: "max-states", 2: "violated", 3: "interrupted"}


@cache
def library():
    """zsearch.c (with dbm.c, active.c and zprogram.c in front) compiled and loaded, or None without a compiler.

    The text is fixed, not generated: a compiler that refuses it is a defect here, raised as BuildError.
    """
    from runtime.native.build import build, compiler

    cc = compiler()
    if cc is None:
        return None
    source = "\n".join((HERE / name).read_text() for name in ("dbm.c", "active.c", "zprogram.c", "zsearch.c"))
    lib = ctypes.CDLL(str(build(source, cc, what="zone search")), mode=ctypes.RTLD_LOCAL)
    p, i32, i64, dbl = ctypes.c_void_p, ctypes.c_int, ctypes.c_int64, ctypes.POINTER(ctypes.c_double)
    for name, res, args in (
            ("zs_new", p, [i32, dbl, i32, i32]), ("zs_free", None, [p]),
            ("zs_set_program", i32, [p, i64, ctypes.POINTER(i64), i64]),
            ("zs_initial", i32, [p, i64, dbl, PROGRAM]),
            ("zs_run", i32, [p, i64, i32, PROGRAM, PROGRESS, i64, i32]),
            ("zs_counts", None, [p, ctypes.POINTER(i64)]), ("zs_node_column", None, [p, i32, ctypes.POINTER(i64)]),
            ("zs_node_row", None, [p, i64, ctypes.POINTER(i64)]),
            ("zs_step_row", None, [p, i64, ctypes.POINTER(i64)]),
            ("zs_step_grown", None, [p, ctypes.POINTER(ctypes.c_uint8)]),
            ("zs_edges", None, [p, ctypes.POINTER(ctypes.c_int32)]),
            ("zs_members", None, [p, ctypes.POINTER(ctypes.c_int32)]),
            ("zs_guards", None, [p, ctypes.POINTER(i64)]), ("zs_zone", None, [p, i64, dbl]),
            ("zs_results", None, [p, ctypes.POINTER(ctypes.c_int32), dbl, ctypes.POINTER(ctypes.c_int32)]),
            ("zs_set_tables", i32, [p, ctypes.POINTER(i64), i64, p, i64, PROGRAM]), ("zs_set_step", None, [p, p]),
            ("zs_intern", i64, [p, ctypes.POINTER(i64)]), ("zs_state_words", None, [p, i64, ctypes.POINTER(i64)]),
            ("zs_nstates", i64, [p]), ("zs_program", i64, [p, i64, ctypes.POINTER(i64), i64]),
            ("zs_set_interaction", i32, [p, i64, ctypes.POINTER(i64), i64]),
            ("zs_set_por", None, [p, AMPLE]), ("zs_set_invariants", None, [p, i32]), ("zs_set_prune", None, [p, i32]),
            ("zs_set_grow_only", i32, [p, ctypes.POINTER(i32), i32]),
            ("zs_set_ample", i32, [p, ctypes.POINTER(i64), i64]),
            ("zs_node_words", None, [p, ctypes.POINTER(i64), i64, i32, ctypes.POINTER(i64)]),
            ("zs_set_budget", None, [p, i64]), ("zs_program_counts", None, [p, ctypes.POINTER(i64)]),
            ("zs_fail_allocation", None, [i64]), ("zs_allocations", i64, [])):
        fn = getattr(lib, name)
        fn.restype, fn.argtypes = res, args
    return lib


def _dbl(a: np.ndarray):
    return a.ctypes.data_as(ctypes.POINTER(ctypes.c_double))


def _longs(a: np.ndarray):
    return a.ctypes.data_as(ctypes.POINTER(ctypes.c_int64))


#: Nodes after which a search that steps with the quick -O0 build of the compiled step has it built at -O2 beside
#: it (whole DALA on one core: 4.6 s of gcc on the other core, then 1.25x faster); a search this short is
#: over in about a second, and never pays for the second compile.
OPTIMISE_AFTER = 50_000


class CSearch:
    """One C search over a ZoneExplorer's model; ``run`` fills the explorer's nodes and result."""

    def __init__(self, z, lib) -> None:
        self.z, self.lib = z, lib
        self.d = z.n + 1
        self.observers = {atom: slot for slot, atom in enumerate(z.model.observers)}
        ceiling = np.ascontiguousarray(z.ceiling, dtype=np.float64)
        self.ctx = lib.zs_new(self.d, _dbl(ceiling), len(self.observers), int(z.merge))
        if not self.ctx:
            raise MemoryError("zone search: no memory for its context")
        lib.zs_set_invariants(self.ctx, int(z.invariants))
        lib.zs_set_prune(self.ctx, int(z.prune))
        grow = z.grow_only
        if lib.zs_set_grow_only(self.ctx, (ctypes.c_int * max(len(grow), 1))(*grow), len(grow)):
            raise MemoryError("zone search: no memory for its context")
        self.error: BaseException | None = None
        self._program = PROGRAM(self._ask)
        self._inter = PROGRAM(self._ask_interaction)
        self.compiled = z.compiled
        if self.compiled is not None:  # programs written in C on the step's words; Python's where C hands back
            from runtime.zones.ctables import tables

            self.width = self.compiled.width
            cm = self.compiled.model
            table, self.step_ids = tables(z, self.width, set(cm.floats) | set(cm.strings))
            words = np.asarray(table, dtype=np.int64)
            self._lib_of_step = self.compiled.lib
            status = lib.zs_set_tables(self.ctx, _longs(words), len(words), self._step_pointer(),
                                       self.compiled.budget, self._inter)
            if status:
                raise MemoryError("zone search: no memory for the model's tables")
            lib.zs_set_budget(self.ctx, z.program_bytes)
            z._intern = self._intern
            self._single_interactions()
        self._ample = AMPLE(self._ask_ample)
        if z.por is not None:
            lib.zs_set_por(self.ctx, self._ample)
        zone = z.initial_zone()  # the initial states, numbered, and their zone: part of the model, made before it runs
        self.initial = [(self._intern(state) if self.compiled else z.state_id(state), zone)
                        for state in map(z.space.state, z.space.initial_ids)]
        self.violation = (ctypes.c_int32 * (len(self.observers) + 1))()  # what zs_results fills
        self.top, self.top_node = np.zeros(self.d), (ctypes.c_int32 * self.d)()

    def _single_interactions(self) -> None:
        """The rows of the interactions that are their source's only one (rendezvous, lone ports), given to C
        before the search, as a model's edges are built before it runs; those of connectors with triggers, one
        per mask and most never enabled, are asked for when the search first meets them."""
        numbering = self.compiled.model.numbering
        for src, offset in enumerate(numbering.offsets):
            if numbering.single[src] and self._ask_interaction(offset):
                error, self.error = self.error, None
                raise error

    def __del__(self) -> None:
        if getattr(self, "ctx", None):
            self.lib.zs_free(self.ctx)
            self.ctx = None

    def _step_pointer(self) -> int:
        return ctypes.cast(self.compiled.lib.c_successors, ctypes.c_void_p).value

    def _intern(self, state: tuple) -> int:
        """The C search's number of an explorer state (ZoneExplorer.state_id while it runs)."""
        from runtime.native.values import to_words

        words = np.asarray(to_words(self.compiled.model, state), dtype=np.int64)
        got = self.lib.zs_intern(self.ctx, _longs(words))
        if got < 0:
            raise MemoryError("zone search: no memory for a state")
        return got

    def state(self, state_id: int) -> tuple:
        """An explorer state from the C search's words."""
        if self.compiled is None:
            return self.z.states[state_id]
        words = (ctypes.c_int64 * self.width)()
        self.lib.zs_state_words(self.ctx, state_id, words)
        return self.compiled._typed(list(words))

    def _ask(self, state_id: int) -> int:
        """The program callback: never lets an exception into C (it is raised when the search returns)."""
        try:
            words = np.asarray(self.z.program(self.state(state_id), self.observers), dtype=np.int64)
            if self.compiled is not None and self.compiled.lib is not self._lib_of_step:  # a field was widened
                self._lib_of_step = self.compiled.lib
                self.lib.zs_set_step(self.ctx, self._step_pointer())
            return self._set(self.lib.zs_set_program(self.ctx, state_id, _longs(words), len(words)))
        except BaseException as e:  # noqa: BLE001 - re-raised by run()
            self.error = e
            return 1

    def _ask_ample(self, state_id: int, slot: int) -> int:
        """The reduction's callback (a node whose state lets no time pass): the interactions to fire first."""
        try:
            z = self.z
            state = self.state(state_id)
            keep = z.ample(state, self.zone(slot).astype(np.float64), forget=True)
            if keep is None:
                return self._set(self.lib.zs_set_ample(self.ctx, None, -1))
            words = np.asarray(sorted(keep), dtype=np.int64)
            return self._set(self.lib.zs_set_ample(self.ctx, _longs(words), len(words)))
        except BaseException as e:  # noqa: BLE001 - re-raised by run()
            self.error = e
            return 1

    def _ask_interaction(self, number: int) -> int:
        """The interaction callback: what a number of the compiled step stands for."""
        from runtime.zones.ctables import interaction_row

        try:
            row = np.asarray(interaction_row(self.z, number, self.compiled.interaction_index(number),
                                             self.step_ids), dtype=np.int64)
            return self._set(self.lib.zs_set_interaction(self.ctx, number, _longs(row), len(row)))
        except BaseException as e:  # noqa: BLE001 - re-raised by run()
            self.error = e
            return 1

    def _set(self, status: int) -> int:
        """What a callback returns to C once it has handed C its answer: a setter without memory (-9) fails the
        callback with the MemoryError the search raises when it returns."""
        if status == -9:
            self.error = MemoryError("zone search: out of memory")
            return 1
        return status

    def run(self, result, max_states: int | None, progress, stop_at_violation: bool):
        """The search to its end (or its bound), ``result`` filled; the explorer's ``watcher``, if any, is given the
        live result every 1,024 expanded states and at each violation found (the nodes so far readable), and may
        raise to stop the search: its exception is raised here, once ``result`` and the nodes say where it
        stopped."""
        from runtime.zones.model import Unsupported

        z, lib = self.z, self.lib
        watcher = z.watcher

        def tick(nodes, transitions, waiting, memory, depth) -> int:
            try:
                self._optimise(nodes)
                progress.tick(nodes, transitions, waiting, lambda: memory, depth)
                if watcher is not None:
                    self._refresh(result, nodes=False)
                    watcher(result)
            except BaseException as e:  # noqa: BLE001 - raised once the search has stopped
                self.error = e
                return 1
            return 0

        callback = PROGRESS(tick)
        for number, zone in self.initial:
            self._raise(lib.zs_initial(self.ctx, number, _dbl(zone), self._program), Unsupported)
        while True:
            status = lib.zs_run(self.ctx, -1 if max_states is None else max_states, int(stop_at_violation),
                                self._program, callback, 1024, int(watcher is not None))
            if status != 4:
                break
            self._refresh(result, nodes=True)
            try:
                watcher(result)
            except BaseException as e:  # noqa: BLE001 - raised below, as from the progress callback
                self.error, status = e, 3
                break
        if status == 3 and self.error is not None:
            self._refresh(result, nodes=True)
            result.complete, result.stopped = False, STOPPED[3]
            error, self.error = self.error, None
            raise error
        self._raise(status, Unsupported)
        self._refresh(result, nodes=True)
        if status:
            result.complete, result.stopped = False, STOPPED[status]
        return result

    def _optimise(self, nodes: int) -> None:
        """Past :data:`OPTIMISE_AFTER` nodes, have the step compiled at -O2 on another thread; once it is, step
        with it (the same words and numbers: only the speed changes)."""
        compiled = self.compiled
        if compiled is None:
            return
        if nodes >= OPTIMISE_AFTER:
            compiled.optimise_later()
        if compiled.adopt():
            self._lib_of_step = compiled.lib
            self.lib.zs_set_step(self.ctx, self._step_pointer())

    def _refresh(self, result, nodes: bool) -> None:
        """``result`` as the search stands: counts, violations and maxima; with ``nodes``, the explorer's nodes."""
        lib = self.lib
        counts = self.counts()
        result.states, result.discrete, result.transitions, result.merged = counts[0], counts[1], counts[2], counts[3]
        result.pruned, result.revived = counts[16], counts[17]
        self.z.dropped = counts[4]
        violation, top, node = self.violation, self.top, self.top_node
        lib.zs_results(self.ctx, violation, _dbl(top), node)
        for atom, slot in self.observers.items():
            if violation[slot] >= 0:
                result.violations[atom] = violation[slot]
        if violation[len(self.observers)] >= 0:
            result.violations[GOAL] = violation[len(self.observers)]
        for clock in range(1, self.d):
            if node[clock] >= 0:
                result.maxima[clock] = (float(top[clock]), node[clock])
        if nodes:
            self._nodes(counts)

    def counts(self) -> list[int]:
        """zsearch.c's zs_counts: nodes, discrete states, transitions, merged, dropped, steps, edges, members,
        guard words, waiting, error argument, bytes held, then bytes of zones, of states and of programs, steps
        of the partial-order reduction, nodes left unexpanded by pruning and pruned nodes brought back."""
        counts = (ctypes.c_int64 * 18)()
        self.lib.zs_counts(self.ctx, counts)
        return list(counts)

    def programs_let_go(self) -> tuple[int, int]:
        """Programs let go past the budget, and programs written again for a state whose one was let go."""
        return self._program_counts()[:2]

    def programs_held(self) -> int:
        """Programs written in C that the search holds now (those Python wrote are never let go)."""
        return self._program_counts()[2]

    def _program_counts(self) -> tuple[int, int, int]:
        out = (ctypes.c_int64 * 3)()
        self.lib.zs_program_counts(self.ctx, out)
        return out[0], out[1], out[2]

    def memory(self) -> int:
        """Bytes the search holds (zsearch.c's zs_memory)."""
        return self.counts()[11]

    def program(self, state_id: int) -> list[int] | None:
        """The program the search used for a state (None if it needed none)."""
        n = self.lib.zs_program(self.ctx, state_id, None, 0)
        if n == -9:
            raise MemoryError("zone search: out of memory")
        if n < 0:
            return None
        out = (ctypes.c_int64 * n)()
        self.lib.zs_program(self.ctx, state_id, out, n)
        return list(out)

    def passing(self, state: tuple):
        """Where time may pass at a discrete state, as the program the search used says (ZoneExplorer.passing's
        value: ``(before, after, waits)``, None where no time passes), or False where the search needed no program
        for it or Python wrote it (a program C wrote and let go past the budget is written again)."""
        if self.compiled is None:
            return False
        words = self.program(self._intern(state))
        if words is None:
            return False
        at = 1 + words[0]  # the idle clocks
        at += 1 + 3 * words[at]  # the clocks whose ceilings are their place's
        if not words[at]:
            return None
        at += 1

        def bounds() -> list[tuple[int, int, int]]:
            nonlocal at
            count = words[at]
            out = [tuple(words[at + 1 + 3 * k:at + 4 + 3 * k]) for k in range(count)]
            at += 1 + 3 * count
            return out

        before, after = bounds(), bounds()
        waits = []
        count, at = words[at], at + 1
        for _ in range(count):
            b = bounds()
            has_lower, lower, r = words[at], (words[at + 1], words[at + 2]), words[at + 3]
            at += 4
            waits.append((b, r, lower if has_lower else None))
        return before, after, waits

    def _raise(self, status: int, unsupported) -> None:
        if status == -1:
            error, self.error = self.error, None
            raise error
        if status == -2:
            counts = self.counts()
            raise unsupported(f"priority {self.z.model.rules[counts[10]].name}: time waits for a clock condition "
                              "that is not one lower bound")
        if status == -9:
            raise MemoryError("zone search: out of memory")

    def _nodes(self, counts) -> None:
        """The C search's nodes, steps into covered zones and edges as the explorer's ``nodes`` and ``out``, read
        from C as they are asked for (a lasso search walks them all; a trace a few; a search that only counts
        none)."""
        self.back = ReadBack(self, counts)
        self.z.nodes = Nodes(self, counts[0])
        self.steps = Steps(self, counts[5])
        self.z.out = Out(self, counts[0])
        if self.compiled is not None:
            self.z.states = States(self)

    def graph(self):
        """The nodes and steps as arrays, for lassos."""
        from runtime.zones.lassos import Graph

        column, e = self.back.column, self.z.out.edges  # edges as C keeps them, 32-bit, and not copied
        flags = column(9)
        return Graph(column(1, np.int32), (flags & 2) > 0, column(3, np.int32), (flags & 1) > 0, column(4) >= 0,
                     e[:, 0], e[:, 1], e[:, 2], self.steps.grown(), self.z.nodes.__getitem__, self.steps.__getitem__)

    def node_words(self, offset: int) -> np.ndarray:
        """Word ``offset`` of each node's state."""
        states = self.back.column(0)
        if self.compiled is None:
            return np.array([self.z.states[s][offset] for s in states.tolist()], dtype=np.int64)
        ids = np.arange(self.lib.zs_nstates(self.ctx), dtype=np.int64)  # once per discrete state, then per node
        out = np.zeros(len(ids), dtype=np.int64)
        self.lib.zs_node_words(self.ctx, _longs(ids), len(ids), offset, _longs(out))
        return out[states]

    def zone(self, slot: int) -> np.ndarray:
        """A stored zone (single precision, as the search keeps it)."""
        out = np.zeros((self.d, self.d))
        self.lib.zs_zone(self.ctx, slot, _dbl(out))
        return out.astype(np.float32)


class States:
    """The C search's discrete states as explorer states, decoded once each when asked for."""

    def __init__(self, search: CSearch) -> None:
        self.search, self.cache = search, {}

    def __len__(self) -> int:
        return self.search.lib.zs_nstates(self.search.ctx)

    def __getitem__(self, k: int) -> tuple:
        got = self.cache.get(k)
        if got is None:
            got = self.cache[k] = self.search.state(k)
        return got

    def __iter__(self):
        return (self[k] for k in range(len(self)))


class ReadBack:
    """The search's graph as it stood at one refresh, each array read from C the first time it is asked for."""

    def __init__(self, search: CSearch, counts: list[int]) -> None:
        self.search, self.counts = search, counts

    def _read(self, fn: str, count: int, shape: tuple, dtype, head: bool) -> np.ndarray:
        """The array zsearch.c's ``fn`` fills, as large as the search's count ``count`` (of :meth:`CSearch.counts`)
        is now: the search may have gone on since the refresh; ``head``: the refresh's rows only."""
        s = self.search
        out = np.zeros((max(1, s.counts()[count], self.counts[count]), *shape), dtype=dtype)
        getattr(s.lib, fn)(s.ctx, out.ctypes.data_as(ctypes.POINTER(np.ctypeslib.as_ctypes_type(dtype))))
        return out[:self.counts[count]] if head else out

    def column(self, col: int, dtype=np.int64) -> np.ndarray:
        """Column ``col`` of the nodes' rows (zsearch.c's node_row: state, parent, via, by, zone, ...), as ``dtype``:
        the nodes are read a column at a time, a search's millions of them as few numbers as its arrays need."""
        s = self.search
        out = np.zeros(max(1, s.counts()[0], self.counts[0]), dtype=np.int64)
        s.lib.zs_node_column(s.ctx, col, _longs(out))
        return out[:self.counts[0]].astype(dtype, copy=False)

    @cached_property
    def edges(self) -> np.ndarray:
        return self._read("zs_edges", 6, (3,), np.int32, head=True)

    @cached_property
    def guards(self) -> np.ndarray:
        return self._read("zs_guards", 8, (), np.int64, head=False)

    @cached_property
    def members(self) -> np.ndarray:
        return self._read("zs_members", 7, (2,), np.int32, head=False)


class Nodes:
    """Nodes of the C search as :class:`CNode`, each one's row read from C when it is first asked for."""

    ROW = "zs_node_row"

    def __init__(self, search: CSearch, n: int) -> None:
        self.search, self.n, self.cache = search, n, {}

    def __len__(self) -> int:
        return self.n

    def _row(self, k: int) -> list[int]:
        if not 0 <= k < self.n:
            raise IndexError(k)
        row = np.zeros(10, dtype=np.int64)
        getattr(self.search.lib, self.ROW)(self.search.ctx, k, _longs(row))
        return row.tolist()

    def __getitem__(self, k: int):
        if k < 0:
            k += len(self)
        got = self.cache.get(k)
        if got is None:
            got = self.cache[k] = CNode(self.search, self._row(k))
        return got

    def __iter__(self):
        return (self[k] for k in range(len(self)))


class Steps(Nodes):
    """The steps into covered zones, as :class:`Nodes` (a search keeps several times more steps than nodes)."""

    ROW = "zs_step_row"

    def grown(self) -> np.ndarray:
        """Whether time passed in each step."""
        out = np.zeros(max(1, self.n), dtype=np.uint8)
        self.search.lib.zs_step_grown(self.search.ctx, out.ctypes.data_as(ctypes.POINTER(ctypes.c_uint8)))
        return out[:self.n] > 0


class Out:
    """Per node, ``(node holding the successor, the step into it)``, as ZoneExplorer.out."""

    def __init__(self, search: CSearch, n: int) -> None:
        self.search, self.n = search, n

    @property
    def edges(self) -> np.ndarray:
        return self.search.back.edges

    @cached_property
    def _sorted(self) -> tuple[np.ndarray, np.ndarray]:
        """The edges by source, and where each node's start."""
        edges, n = self.edges, self.n
        if not len(edges):
            return edges, np.zeros(n + 1, int)
        order = edges[np.argsort(edges[:, 0], kind="stable")]
        return order, np.searchsorted(order[:, 0], np.arange(n + 1))

    def __len__(self) -> int:
        return self.n

    def __getitem__(self, k: int) -> list:
        s = self.search
        ordered, starts = self._sorted
        out = []
        for _, target, ref in ordered[starts[k]:starts[k + 1]].tolist():
            out.append((target, s.z.nodes[ref] if ref >= 0 else s.steps[-ref - 1]))
        return out

    def __iter__(self):
        return (self[k] for k in range(self.n))


class CNode(Node):
    """A node of the C search: its state and zones read from C the first time they are asked for."""

    __slots__ = ("_search", "_sid", "_slot", "_own_slot")

    def __init__(self, search: CSearch, row: list) -> None:
        state, parent, via, by, slot, own, first, goff, glen, flags = row
        g = search.back.guards[goff:goff + 3 * glen].tolist()
        super().__init__(None, None, parent, via, list(zip(g[0::3], g[1::3], g[2::3])), bool(flags & 1))
        self._search, self._sid, self._slot, self._own_slot = search, state, slot, own
        self.covered, self.expanded, self.dead, self.by = bool(flags & 2), bool(flags & 4), bool(flags & 8), by
        while first >= 0:
            members = search.back.members
            self.members.append(int(members[first, 0]))
            first = int(members[first, 1])

    @property
    def state(self) -> tuple:
        return self._search.z.states[self._sid]

    @state.setter
    def state(self, value) -> None:
        pass  # Node.__init__ sets it: here it always comes from the search

    @property
    def stored(self) -> np.ndarray | None:
        if self._zone is None and self._slot >= 0:
            self._zone = self._search.zone(self._slot)
        return self._zone

    @property
    def zone(self) -> np.ndarray | None:
        return _double(self.stored)

    @zone.setter
    def zone(self, m) -> None:
        self._zone = m

    @property
    def own(self) -> np.ndarray | None:
        if self._own is None and self._own_slot >= 0:
            self._own = self._search.zone(self._own_slot)
        return _double(self._own)

    @own.setter
    def own(self, m) -> None:
        self._own = m

    @property
    def reached(self) -> np.ndarray | None:
        return self.own if self._own_slot >= 0 else self.zone
