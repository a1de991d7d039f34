"""Random runs in C (srun.c) on the compiled step: Simulator.run's loop and policy without a Python call per step.

The C loop asks Python what the policy needs of an interaction the first time it meets it (the same ``_Info``,
weights and duration laws the Python loop uses) and draws from xoshiro256** seeded with words that
:func:`runtime.smc.simulate.run_seed` gives for ``(seed, index)``: a run depends on its seed and index alone,
wherever it is computed.  Its runs follow the Python loop's distribution, not its random stream.
"""
from __future__ import annotations

import ctypes
import math
from functools import cache
from pathlib import Path

HERE = Path(__file__).parent
I64, I32, DBL = ctypes.c_int64, ctypes.c_int, ctypes.c_double
P64, P32, PDBL = ctypes.POINTER(I64), ctypes.POINTER(I32), ctypes.POINTER(DBL)
DEFINE = ctypes.CFUNCTYPE(I32, I64, I64, P64)
ENDS = {0: "horizon", 1: "goals", 2: "deadlock", 3: "zeno"}
ERR_STEP, ERR_DEFINE = -1, -3
LAWS = {"uniform": 0, "triangular": 1, "normal": 2}
WIDEN, ROOM = 8, 10  # the compiled step's codes: a field too narrow; more successors than room


@cache
def library():
    """srun.c compiled and loaded (None without a C compiler)."""
    from runtime.native.build import build, compiler

    cc = compiler()
    if cc is None:
        return None
    lib = ctypes.CDLL(str(build((HERE / "srun.c").read_text(), cc, what="SMC runs")), mode=ctypes.RTLD_LOCAL)
    p = ctypes.c_void_p
    for name, res, args in (
            ("sr_new", p, [I32, I32, P64, I32, P64, I32, P64, I32, I32, P64, I32, P64, I32, P64, I32, P64, I32, DBL,
                           I32]),
            ("sr_free", None, [p]), ("sr_forget", None, [p]), ("sr_set_step", None, [p, p, I64, p]),
            ("sr_define", I32, [p, I64, I32, P32, P32, I64, PDBL, P32, PDBL]),
            ("sr_run", I32, [p, P64, ctypes.POINTER(ctypes.c_uint64), I64, I64, I32]),
            ("sr_results", None, [p, P64]), ("sr_goals", None, [p, P64, P64]), ("sr_responses", None, [p, P64]),
            ("sr_choices", None, [p, P64])):
        fn = getattr(lib, name)
        fn.restype, fn.argtypes = res, args
    return lib


def _longs(values) -> ctypes.Array:
    values = list(values)
    return (I64 * max(1, len(values)))(*values)


class CRuns:
    """The runs of ``sim`` (a :class:`runtime.smc.Simulator` on the compiled step) computed in C."""

    def __init__(self, sim, lib) -> None:
        self.sim, self.lib = sim, lib
        step = sim.step
        self.cs, self.w = step.cs, step.w
        sched = [v for _, mark, busy, x, lo, hi in sim.scheds for v in (mark, busy, x, lo, hi)]
        win = []
        for mark, bit, clock, lo, hi in sim.windows:
            win += [mark, bit, clock]
            for kind, v in (lo, hi):
                win += [v, 0] if kind == "slot" else [-1, v]
        goals = [v for slot, bit in sim.goal_slots for v in (slot, bit)]
        leaps = sim.leaps
        clocks = leaps.clocks if leaps else []
        cons = [v for pair in (leaps.consts if leaps else []) for v in pair]
        dyn = [v for pair in (leaps.dynamic if leaps else []) for v in pair]
        gaps = [v for g in (leaps.gaps if leaps else []) for v in (g.i if g.i is not None else -1,
                                                                      g.j if g.j is not None else -1, g.k)]
        cfg = sim.config
        self.ctx = lib.sr_new(self.w, len(sim.scheds), _longs(sched), len(sim.windows), _longs(win),
                              len(sim.goal_slots), _longs(goals), len(cfg.watches), len(clocks), _longs(clocks),
                              len(cons) // 2, _longs(cons), len(dyn) // 2, _longs(dyn), len(gaps) // 3, _longs(gaps),
                              int(leaps is not None), float(cfg.tick_us), int(cfg.keep_going))
        if not self.ctx:
            raise MemoryError("SMC runs in C: no memory for their context")
        self.error: BaseException | None = None
        self.defined: dict[tuple[int, int], tuple] = {}  # (number, count) -> sr_define's arguments
        self._define = DEFINE(self._on_define)
        self._bind()

    def __del__(self) -> None:
        if getattr(self, "ctx", None):
            self.lib.sr_free(self.ctx)
            self.ctx = None

    def _bind(self) -> None:
        succ = ctypes.cast(self.cs.lib.c_successors, ctypes.c_void_p).value
        self.lib.sr_set_step(self.ctx, succ, self.cs.budget, ctypes.cast(self._define, ctypes.c_void_p).value)

    def _on_define(self, number: int, count: int, words) -> int:
        """What the policy needs of interaction ``number`` with ``count`` successors in state ``words``."""
        try:
            sim = self.sim
            info = sim.info(number)
            args = self.defined.get((number, count))
            if args is not None:  # seen with this many successors before: the same answer, without the engine
                return self.lib.sr_define(self.ctx, number, *args)
            made = None
            if count > 1 or info.execs:
                state = self.cs._typed(words[:self.w])
                made = [m for inter, _, m in sim.space._fire_all(state) if inter.index == info.index]
                if len(made) != count:
                    made = None
            weights = [sim._weight(info, m) for m in made] if made is not None else [1.0] * count
            laws = [sim._duration(info, m) for m in made] if made is not None else [None] * count
            lists = (info.execs, info.dones, info.ends, info.opens, info.closes, info.hits, info.cancels)
            lens = (I32 * len(lists))(*(len(x) for x in lists))
            items = [v for x in lists for v in x]
            params = []
            for law in laws:
                params += [math.nan if v is None else float(v) for v in
                           ((law.mode_us, law.mean_us, law.sd_us) if law is not None else (None, None, None))]
            kinds = [LAWS.get(law.kind, 0) if law is not None else 0 for law in laws]
            args = (int(info.tick), lens, (I32 * max(1, len(items)))(*items), count, (DBL * max(1, count))(*weights),
                    (I32 * max(1, count))(*kinds), (DBL * max(3, 3 * count))(*params))
            self.defined[(number, count)] = args
            return self.lib.sr_define(self.ctx, number, *args)
        except BaseException as exc:  # raised again by run(), not lost in the callback
            self.error = exc
            return -1

    def run(self, seed_words: list[int], start: tuple, horizon: int, limit: int, record: bool):
        """``(end, reached, at_step, responses, ticks, steps, choices)`` of one run (choices: (number, rank))."""
        lib, ctx = self.lib, self.ctx
        seeds = (ctypes.c_uint64 * 4)(*seed_words)
        while True:
            init = _longs(self.sim.step.to_words(self.cs.model, start))
            status = lib.sr_run(ctx, init, seeds, horizon, limit, int(record))
            if status >= 0:
                break
            if status == ERR_DEFINE and self.error is not None:
                error, self.error = self.error, None
                raise error
            out = (I64 * 6)()
            lib.sr_results(ctx, out)
            if status == ERR_STEP and out[4] == WIDEN and self.cs.lib.c_width(out[5]) < 64:
                # a field too narrow: widen (a rebuild), run again
                self.cs._widen(out[5])
                self.sim.step.numbers.clear()
                self.sim.infos.clear()
                self.defined.clear()
                lib.sr_forget(ctx)
                self._bind()
                continue
            if status == ERR_STEP:
                from runtime.native.compiled import _CError

                raise _CError(out[4], out[5])
            raise MemoryError(f"SMC runs in C: status {status}")
        out = (I64 * 6)()
        lib.sr_results(ctx, out)
        ticks, steps, nresp, nchoice = out[0], out[1], out[2], out[3]
        n = len(self.sim.goal_slots)
        reached, at_step = (I64 * max(1, n))(), (I64 * max(1, n))()
        lib.sr_goals(ctx, reached, at_step)
        responses: list[list[int]] = [[] for _ in self.sim.config.watches]
        if nresp:
            pairs = (I64 * (2 * nresp))()
            lib.sr_responses(ctx, pairs)
            for k in range(nresp):
                responses[pairs[2 * k]].append(pairs[2 * k + 1])
        choices = None
        if record:
            pairs = (I64 * max(2, 2 * nchoice))()
            lib.sr_choices(ctx, pairs)
            choices = [(pairs[2 * k], pairs[2 * k + 1]) for k in range(nchoice)]
        return (ENDS[status], [None if reached[g] < 0 else reached[g] for g in range(n)],
                [None if at_step[g] < 0 else at_step[g] for g in range(n)], responses, ticks, steps, choices)
