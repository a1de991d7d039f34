"""Traces of statistical model checking: the first run that reached an observer's ERROR, rebuilt with the Python
step (codel outcomes named), and a trace written as JSON replayed on the engine."""
from __future__ import annotations

from typing import Any

from genom2bip.verify.model import Model
from genom2bip.verify.results import Trace, timed
from genom2bip.verify.smc_results import SmcResult
from runtime.smc import Simulator



def witness(sim: Simulator, seed: int, result: SmcResult) -> Trace | None:
    """The run that first reached ``result``'s phi, up to the step that reached it, as a timed trace of the model
    (rebuilt with the Python step, codel outcomes included); None when no run reached it."""
    if result.first_run is None:
        return None
    goal = next(k for k, g in enumerate(sim.config.goals) if g.atom == result.observer)
    run = sim.run(seed, result.first_run, record=True)
    cut = run.reached_steps[goal]
    if cut is None:  # not the same run: the simulator is not deterministic
        raise RuntimeError(f"run {result.first_run} of seed {seed} did not reach {result.subject} again")
    space = sim.space
    state = space.state(run.start)
    steps = []
    from runtime.explore.space import Step

    choices = run.choices[:cut]
    k = 0
    while k < len(choices):
        index, rank = choices[k]
        options = [(inter, nxt, made) for inter, nxt, made in space._fire_all(state) if inter.index == index]
        inter, nxt, made = options[min(rank, len(options) - 1)]
        if inter.label == sim.config.tick_label and sim.leaps is not None:
            # a run of ticks: those that only add to clocks (Leaps.length) rebuilt by arithmetic, not one by one
            ticks = next((j for j in range(k, len(choices)) if choices[j][0] != index), len(choices)) - k
            rates = {slot: nxt[slot] - state[slot] for slot in sim.leaps.clocks}
            span = sim.leaps.length(lambda slot, s=state: s[slot], rates)
            if span > 1:
                n = min(ticks, span - 1)
                ahead = list(state)
                for slot, r in rates.items():
                    ahead[slot] += r * n
                state = tuple(ahead)
                steps.extend([Step(inter.label, index, (), ())] * n)
                k += n
                continue
        state = nxt
        steps.append(Step(inter.label, index, tuple((c.name, pos) for c, pos in made),
                          tuple(c.describe(pos) for c, pos in made)))
        k += 1
    return timed(steps, sim.config.tick_us)


def replay(model: Model, trace: dict[str, Any], atom: str | None = None) -> tuple:
    """Replay a trace written as JSON (``Trace.to_json()``) on the model's engine, step by step, each step's codel
    outcomes as written; the engine state reached.  ``atom``: the observer that must be in ERROR at the end.
    ValueError naming the step that does not replay."""
    from runtime.explore import StateSpace

    space = StateSpace(model.package, model.root, None, None, False, set())
    state = space.state(space.initial_ids[0])
    for n, item in enumerate(trace["steps"], 1):
        names = tuple(item.get("outcomes", ()))
        options = space._fire_all(state)
        match = next((nxt for inter, nxt, made in options if inter.label == item["label"]
                      and tuple(c.describe(p) for c, p in made) == names), None)
        if match is None:
            enabled = ", ".join(sorted({i.label for i, _, _ in options})) or "none"
            raise ValueError(f"step {n} ({item['label']}) does not replay: enabled are {enabled}")
        state = match
    if atom is not None:
        fa = next(a for a in space.engine.flat.atoms if a.name == atom)
        if not state[fa.offset] & (1 << fa.places.index("ERROR")):
            raise ValueError(f"the trace replays but {atom} is not in ERROR at its end")
    return state
