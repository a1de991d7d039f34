"""The engine: a package instantiated from a root spec, its step compiled once, and a run loop.

``initial_state``, ``enabled`` and ``fire`` are the whole semantics; the
explorer calls exactly these, breadth-first, where ``run`` lets a policy
choose.  States are flat tuples (see docs/engine.md), hashable and compact.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

from runtime.engine import defines, support
from runtime.engine.cexpr import HELPERS
from runtime.engine.codegen import CodeGen, ErrorSite, generate
from runtime.engine.errors import EngineError, ModelError
from runtime.engine.extern_ports import ExternPorts, UnexpectedEvent
from runtime.engine.externs import bind_externs, guarded_call
from runtime.engine.flatten import flatten
from runtime.engine.interaction import Interaction, interaction_label
from runtime.engine.invariants import InvariantViolation, Invariants
from runtime.engine.plan import Source, TreeNode, parts, plan
from runtime.engine.source import compile_generated
from runtime.model import Package

State = tuple
Policy = Callable[[State, list[Interaction]], "Interaction | None"]


@dataclass
class RunSummary:
    """How a run ended: ``outcome`` is ``deadlock``, ``limit``, ``error``, ``invariant`` (an atom invariant
    failed), ``event`` (an extern port with policy ``error`` got an event it cannot take) or ``stopped``."""

    steps: int
    outcome: str
    message: str = ""
    state: State | None = None
    enabled: list[str] = field(default_factory=list)

    def line(self) -> str:
        what = {"deadlock": "deadlock (no enabled interaction)", "limit": "step limit reached",
                "stopped": "stopped", "error": f"model error: {self.message}",
                "invariant": f"invariant violated: {self.message}",
                "event": f"unexpected event: {self.message}"}[self.outcome]
        return f"{self.steps} step{'s' if self.steps != 1 else ''}, {what}"


def _raisers(errors: list[ErrorSite]) -> dict[str, Callable]:
    """The error functions the generated code calls with the index of a static :class:`ErrorSite`."""
    def nondet(k, flags):
        e = errors[k]
        ts = tuple(t for t, f in zip(e.transitions, flags) if f)
        raise ModelError(e.message, atom=e.atom, port=e.port, transitions=ts)

    def unsafe(k, bits):
        e = errors[k]
        places = tuple(p for i, p in enumerate(e.places) if bits >> i & 1)
        raise ModelError(e.message, atom=e.atom, port=e.port, places=places, transitions=tuple(e.transitions))

    def plain(k):
        e = errors[k]
        raise ModelError(e.message, atom=e.atom, port=e.port, transitions=tuple(e.transitions))

    return {"_nondet": nondet, "_unsafe": unsafe, "_stuck": plain, "_notenabled": plain}


@dataclass(frozen=True)
class CompiledStep:
    """The generated step's own entry points, for tools that drive the same semantics in bulk (the explorer).

    ``enabled(state)`` lists the enabled interactions; ``fire[source](state,
    mask, record)`` fires the interaction ``(source, mask)`` of one source
    (``record``: None, or a dict that receives the port values);
    ``interaction(source, mask)`` gives the :class:`Interaction` object.
    """

    enabled: Callable[[State], list[Interaction]]
    fire: tuple[Callable[..., State], ...]
    interaction: Callable[[int, int], Interaction]


class Engine:
    """A runnable model. ``Engine(package, root="System()", externs=None)``.

    ``externs`` binds the ``extern function`` names the model calls: a dict of
    callables, a module, or a module's dotted name or ``.py`` path.  Unbound
    names raise :class:`ExternError` here, before any step.  ``maximal_progress=False`` offers every
    enabled interaction of a connector, not only the maximal ones (the Verimag engine's
    ``--disable-maximal-progress``).
    """

    def __init__(self, package: Package, root: str = "System()", externs: Any = None,
                 maximal_progress: bool = True) -> None:
        self.package = package
        self.root = root
        self.flat = flatten(package, root)
        self.infos, self.sources = plan(self.flat, maximal_progress)
        #: events pushed into the extern ports (``engine.extern.push("a.p", 3)``); None when there is none
        self.extern: ExternPorts | None = ExternPorts(self.flat, self.sources)
        if not self.extern.ports:
            self.extern = None
        gen = generate(self.flat, self.infos, self.sources)
        self.source: str = gen.source
        bound = bind_externs(package, externs, gen.called)
        self._caches: list[dict[int, Interaction]] = [{} for _ in self.sources]
        ns: dict[str, Any] = dict(HELPERS)
        ns.update(_raisers(gen.errors))
        ns.update({f"_x_{name}": guarded_call(name, fn) for name, fn in bound.items()})
        ns["_NONE"] = (None, None, None)
        ns["_max_allowed"] = defines.max_allowed
        ns["_maximal_enabled"] = defines.maximal_enabled
        ns["_mk"] = self._make
        for name, k in gen.type_index.items():
            ns[f"_T{k}"] = self.infos[name].tree
        for i, (order, rules, texts, guarded) in gen.atom_priorities.items():
            ns[f"_aprio{i}"] = support.AtomPriorities(self.flat.atoms[i].name, order, rules, texts, guarded)
        for src in self.sources:
            ns[f"_IC{src.index}"] = self._caches[src.index]
            if src.kind in ("port", "rendezvous"):
                ns[f"_I{src.index}_{src.full}"] = self._make(src.index, src.full)
            if src.kind == "generic":
                ns[f"_S{src.index}"] = src
        self.code = compile_generated(self.source, f"bip step: {package.name} {root}")
        exec(self.code, ns)  # noqa: S102 - our own generated source
        self.namespace = ns
        slots = tuple(p.slots for p in self.flat.ports)
        fire_port = tuple(ns[f"_ap{p.id}"] for p in self.flat.ports)
        ns["_generic"] = lambda src, s, E: support.generic_enabled(src, s, E, slots)
        ns["_fire_tree"] = lambda src, L, mask, rec: support.fire_tree(src, L, mask, rec, slots, fire_port)
        for src in self.sources:
            if src.tree is not None:
                self._attach(src.tree, gen.type_index, ns)
        if self.flat.priorities:
            rules = [(p.text, p.low.entries, p.high.entries, ns.get(f"_pg{r}"))
                     for r, p in enumerate(self.flat.priorities)]
            ns["_prio"] = support.Priorities(rules, support.top_connectors(self.sources)).filter
        self._initial = ns["initial"]
        self._enabled = ns["enabled"]
        self._fire = ns["FIRE"]
        self.invariants = Invariants(self.flat, ns)
        if self.invariants:
            initial, check = self._initial, self.invariants.check
            self._initial = lambda: check(initial())
            self._fire = [self.invariants.guard_fire(f, lambda mask, k=k: self._make(k, mask).label)
                          for k, f in enumerate(self._fire)]
        self.step = CompiledStep(self._enabled, tuple(self._fire), self._make)
        self._ready = None

    def _attach(self, node: TreeNode, type_index: dict[str, int], ns) -> None:
        info = node.info
        node.runtime = support.Clauses(ns[f"_K{type_index[info.type.name]}"], info.local_defaults, info.export_idx)
        for alts in node.params:
            for a in alts:
                if a.node is not None:
                    self._attach(a.node, type_index, ns)

    # -- interactions ----------------------------------------------------------------------------
    def _make(self, src_index: int, mask: int) -> Interaction:
        """The Interaction ``(source, mask)``, created once and cached."""
        cache = self._caches[src_index]
        got = cache.get(mask)
        if got is None:
            src = self.sources[src_index]
            path = src.connector.path if src.connector is not None else None
            got = cache[mask] = Interaction(mask * len(self.sources) + src_index, src_index, mask, path, self._describe)
        return got

    def interaction(self, index: int) -> Interaction:
        """The interaction whose ``index`` a trace step recorded (``mask * sources + source``)."""
        n = len(self.sources)
        if index < 0:
            raise KeyError(index)
        return self._make(index % n, index // n)

    def _describe(self, inter: Interaction) -> tuple:
        """Ports, label and parts of an interaction, worked out when first asked for."""
        src: Source = self.sources[inter.source]
        mask = inter.mask
        if src.kind == "port":
            return (src.port.path,), interaction_label(None, [src.port.path], True), ()
        fc = src.connector
        ports = [self.flat.ports[p] for i, p in enumerate(src.leaves) if mask >> i & 1]
        cut = len(fc.scope) + 1 if fc.scope else 0
        label = interaction_label(fc.label, [p.path[cut:] for p in ports], mask == src.full and not src.alternatives,
                                 fc.named and not src.alternatives)
        return tuple(p.path for p in ports), label, tuple(parts(src.tree, mask))

    # -- the semantics ---------------------------------------------------------------------------
    def initial_state(self) -> State:
        """Initial transitions of every atom, then their eager internal transitions."""
        try:
            return self._initial()
        except Exception as err:
            raise self._model_error(err) from err

    def enabled(self, state: State) -> list[Interaction]:
        """Interactions that may fire at ``state``, after maximal progress and priorities, in a fixed order."""
        try:
            return self._enabled(state)
        except Exception as err:
            raise self._model_error(err) from err

    def ready(self, state: State) -> tuple[bool, ...]:
        """Per atom port (``flat.ports`` order): the atom offers it at ``state``, its own priorities applied.

        What an interaction that is not enabled lacks; the function is generated at the first call.
        """
        if self._ready is None:
            gen = CodeGen(self.flat, self.infos, self.sources).generate_ready()
            ns = dict(self.namespace)
            ns.update(_raisers(gen.errors))
            exec(compile_generated(gen.source, f"bip ready: {self.package.name} {self.root}"), ns)  # noqa: S102
            self._ready = ns["ready"]
        try:
            return self._ready(state)
        except Exception as err:
            raise self._model_error(err) from err

    def fire(self, state: State, interaction: Interaction) -> State:
        """The state after firing ``interaction`` (which must be enabled at ``state``)."""
        try:
            return self._fire[interaction.source](state, interaction.mask, None)
        except Exception as err:
            raise self._model_error(err) from err

    def offered(self, state: State, steps: int = 0) -> list[Interaction]:
        """What a run may fire at ``state`` after ``steps`` steps: :meth:`enabled`, with each extern port only
        while an event is pending for it (runtime.engine.extern_ports); events arrive first and, while nothing
        can fire, the next ones come."""
        enabled = self.enabled(state)
        if self.extern is None:
            return enabled
        self.extern.arrive(steps)
        offered = self.extern.settle(enabled)  # UnexpectedEvent for a port whose policy is error
        while not offered and self.extern.next_arrival() is not None:
            self.extern.arrive(max(steps, self.extern.next_arrival()))
            offered = self.extern.settle(enabled)
        return offered

    def _fire_event(self, state: State, source: int, rec) -> State:
        """Fire the extern port of ``source`` with the values of the event it takes."""
        L = list(state)
        self.namespace[f"_ap{self.sources[source].port.id}"](L, self.extern.take(source), rec)
        new = tuple(L)
        if self.invariants:
            return self.invariants.check(new, self._make(source, self.sources[source].full).label)
        return new

    def fire_traced(self, state: State, interaction: Interaction) -> tuple[State, dict[str, dict[str, Any]]]:
        """Like :meth:`fire`, and also the values each atom port received (after ``down``), by ``atom.port``;
        an extern port takes the values of its pending event."""
        rec: list[tuple[int, tuple]] = []
        try:
            if self.extern is not None and interaction.source in self.extern.by_source:
                new = self._fire_event(state, interaction.source, rec)
            else:
                new = self._fire[interaction.source](state, interaction.mask, rec)
        except Exception as err:
            raise self._model_error(err) from err
        values = {}
        for pid, vals in rec:
            fp = self.flat.ports[pid]
            values[fp.path] = dict(zip(fp.fields, vals))
        return new, values

    def successors(self, state: State) -> list[tuple[Interaction, State]]:
        """Every enabled interaction with the state it leads to: one breadth-first expansion."""
        return [(i, self.fire(state, i)) for i in self.enabled(state)]

    def _model_error(self, err: Exception) -> Exception:
        """What a failure inside the generated step becomes: a ModelError saying where it happened."""
        if isinstance(err, ModelError):
            if err.atom is None and err.__traceback__ is not None:
                return ModelError(f"{err.message}{self._where(err)}", port=err.port, places=err.places,
                                  transitions=err.transitions)
            return err
        if isinstance(err, EngineError):
            return err
        if isinstance(err, RecursionError):
            return ModelError("recursion too deep while evaluating the model")
        # a guard or action failed (ill-typed expression, ...)
        return ModelError(f"evaluation failed: {type(err).__name__}: {err}{self._where(err)}")

    def _where(self, err: BaseException) -> str:
        """Where in the generated step an error happened: the function's docstring and the source line."""
        tb = err.__traceback__
        frame = None
        while tb is not None:
            if tb.tb_frame.f_code.co_filename == self.code.co_filename:
                frame = tb
            tb = tb.tb_next
        if frame is None:
            return ""
        lines = self.source.splitlines()
        n = frame.tb_lineno - 1
        line = lines[n].strip() if 0 <= n < len(lines) else ""
        where = None
        for k in range(n, max(frame.tb_frame.f_code.co_firstlineno - 1, 0), -1):
            text = lines[k].strip()
            if text.startswith(("# atom ", "# connector ")):
                where = text[2:]
                break
        if where is None:
            fn = self.namespace.get(frame.tb_frame.f_code.co_name)
            doc = (fn.__doc__ or "").strip() if fn is not None else ""
            where = doc.splitlines()[0].rstrip(".") if doc else frame.tb_frame.f_code.co_name
        return f" (in {where}: {line})"

    def find(self, state: State, label: str) -> Interaction:
        """The enabled interaction with this label (for tests and scripted runs)."""
        for i in self.enabled(state):
            if i.label == label:
                return i
        raise KeyError(f"no enabled interaction labelled {label!r}; enabled: {[i.label for i in self.enabled(state)]}")

    # -- states ------------------------------------------------------------------------------------
    def describe_state(self, state: State) -> dict[str, dict[str, Any]]:
        """Marked places and variables of every atom: ``{atom: {"places": [...], "data": {...}}}``."""
        out = {}
        for fa in self.flat.atoms:
            m = state[fa.offset]
            out[fa.name] = {
                "places": [p for i, p in enumerate(fa.places) if m >> i & 1],
                "data": {d.name: state[fa.slot(d.name)] for d in fa.variables},
            }
        return out

    def format_state(self, state: State) -> str:
        """One line per atom: ``name: PLACE x=1 y=2``."""
        lines = []
        for name, st in self.describe_state(state).items():
            data = " ".join(f"{k}={v!r}" for k, v in st["data"].items())
            lines.append(f"{name}: {','.join(st['places']) or '-'}" + (f" {data}" if data else ""))
        return "\n".join(lines)

    # -- running ---------------------------------------------------------------------------------------
    def run(self, policy: Policy, limit: int | None = None, tracer=None) -> RunSummary:
        """Step from the initial state, ``policy`` choosing, until deadlock, ``limit`` steps, an error or a stop."""
        steps = 0
        state = None
        try:
            state = self.initial_state()
            if tracer is not None:
                tracer.start(self, state)
            while True:
                enabled = self.offered(state, steps) if self.extern is not None else self.enabled(state)
                if not enabled:
                    summary = RunSummary(steps, "deadlock", state=state)
                    break
                if limit is not None and steps >= limit:
                    summary = RunSummary(steps, "limit", state=state, enabled=[i.label for i in enabled])
                    break
                chosen = policy(state, enabled)
                if chosen is None:
                    summary = RunSummary(steps, "stopped", state=state, enabled=[i.label for i in enabled])
                    break
                if tracer is not None or self.extern is not None:
                    new, values = self.fire_traced(state, chosen)
                    steps += 1
                    if tracer is not None:
                        tracer.step(steps, enabled, chosen, values, new)
                else:
                    new = self.fire(state, chosen)
                    steps += 1
                state = new
        except InvariantViolation as err:
            summary = RunSummary(steps, "invariant", str(err), state=state)
        except UnexpectedEvent as err:
            summary = RunSummary(steps, "event", str(err), state=state)
        except ModelError as err:
            summary = RunSummary(steps, "error", str(err), state=state)
        if tracer is not None:
            tracer.finish(summary)
        return summary

