"""Calling Python codels from the model's codel externs: arguments in, outcome index out.

The engine calls ``NDD_nddPlan()`` with no argument and expects the outcome
index (runtime/codels.py).  The extern made here finds who is running (the
service or task the firing interaction belongs to, set by the controller in
:attr:`Binder.scope`), builds the codel's keyword arguments from the ids, the
request's parameters and locals, and the posters, calls the Python function,
writes ``out``/``inout`` holders back, and maps the yield (or the exception)
to the outcome.  Anything wrong becomes :attr:`Binder.failure`, with the
codel's name, and the undeclared outcome: the service fails, the controller
keeps running.

Each call is a :class:`CodelCall`, which the watchdog reads
(runtime.controller.stuck): a call past its bound may be *detached*, the
engine going on without it in another thread; when the codel returns, its
outcome waits in the call, and the controller fires the step again with
:attr:`Binder.replay` holding it, so that the codel is not called twice.
With :attr:`Binder.times` set, every call's CPU and wall time from that same
start is recorded under ``Module.Owner.codel``
(runtime.controller.codel_times).
"""
from __future__ import annotations

import threading
import time
import traceback
from dataclasses import dataclass, field
from typing import Any, Callable

from runtime.codels import UNDECLARED, CodelSpec
from runtime.controller.codel_times import CodelTimes
from runtime.controller.codels import CodelSource
from runtime.controller.data import Data, clone, get_path, path_steps, set_path
from runtime.controller.schema import checker, problems
from runtime.genom import Ref, Throw


class CodelInterrupted(BaseException):
    """Raised inside a codel that would not return after the controller was told to stop."""


class CodelDetached(BaseException):
    """Raised in the thread of a detached codel once it returns: the engine went on in another thread.

    ``args[0]`` is the :class:`CodelCall`.
    """


@dataclass
class Arg:
    """How one argument is made: ``source`` ids/local/port/remote, ``direction``, the variable's path."""

    name: str
    source: str
    direction: str
    steps: list[str | int]
    port: str = ""

    @classmethod
    def of(cls, spec: dict[str, Any]) -> "Arg":
        steps = path_steps(spec["path"])
        return cls(spec["arg"], spec["source"], spec["direction"], steps, str(steps[0]) if steps else "")


@dataclass
class Scope:
    """A service or a task of a component: whose codels run, with which argument lists (by extern name)."""

    component: str
    name: str
    kind: str  # "service" or "task"
    codels: dict[str, list[Arg]] = field(default_factory=dict)

    @property
    def label(self) -> str:
        return f"{self.component}.{self.name}"

    @property
    def posters(self) -> list[str]:
        """The posters (port out) its codels write."""
        return sorted({a.port for args in self.codels.values() for a in args
                       if a.source == "port" and a.direction != "in"})


@dataclass(eq=False)
class CodelCall:
    """One call of a codel: whose, since when, in which thread; once detached, its outcome when it comes.

    ``outcome`` is ``("return", value)`` or ``("raise", exception)``;
    ``abandoned`` says why the controller gave up waiting for it.
    """

    codel: str
    extern: str
    component: str
    scope: Scope | None
    locals: dict[str, Any] | None
    holders: list[tuple[Arg, Any]]
    started: float  # time.monotonic() when the call began (the watchdog's and the wall time's start)
    thread: threading.Thread
    cpu_started: float = 0.0  # time.thread_time() of the calling thread when the call began
    reported: bool = False  # the watchdog has said it runs past its bound
    detached: bool = False
    done: bool = False
    outcome: tuple[str, Any] | None = None
    abandoned: str | None = None
    lock: threading.Lock = field(default_factory=threading.Lock)

    def finish(self, outcome: tuple[str, Any]) -> bool:
        """The codel returned: True when the step that called it goes on, False when it was detached."""
        with self.lock:
            self.done = True
            if self.abandoned is None:
                self.outcome = outcome
            return not self.detached

    def detach(self) -> bool:
        """Let the engine go on without this call (False: it has just returned, or is detached already: the
        watchdog and a remote call may both want to, and only one engine thread may go on)."""
        with self.lock:
            if self.done or self.detached:
                return False
            self.detached = True
            return True

    def abandon(self, why: str) -> None:
        """Give up on a detached call that has not returned: its step fails with ``why``."""
        with self.lock:
            if not self.done:
                self.abandoned = why

    @property
    def settled(self) -> bool:
        """A detached call whose step can be fired again: it returned, or was given up on."""
        return self.done or self.abandoned is not None


def scopes(interface: dict[str, Any]) -> tuple[dict[str, Scope], dict[str, Scope]]:
    """Services and tasks of the interface as scopes, by ``Component.Name``."""
    services: dict[str, Scope] = {}
    tasks: dict[str, Scope] = {}
    for c, spec in interface["components"].items():
        for s, svc in spec["services"].items():
            services[f"{c}.{s}"] = Scope(c, s, "service", {x: [Arg.of(a) for a in k["params"]]
                                                              for x, k in svc["codels"].items()})
        for t, task in spec["tasks"].items():
            tasks[f"{c}.{t}"] = Scope(c, t, "task", {x: [Arg.of(a) for a in k["params"]]
                                                     for x, k in task["codels"].items()})
    return services, tasks


class Binder:
    """Makes the codel externs of a model; the controller sets :attr:`scope` and :attr:`locals` before each step.

    ``failure`` is set by a codel call that did not end with a declared
    outcome (or that threw a declared exception: then it carries the
    exception's name and detail); the controller takes it after the step.
    ``on_poster(component, port, value)`` is told about every poster write.
    """

    def __init__(self, interface: dict[str, Any], data: Data, source: CodelSource,
                 specs: dict[str, CodelSpec], on_poster: Callable[[str, str, Any], None] | None = None) -> None:
        self.interface = interface
        self.data = data
        self.source = source
        self.specs = specs
        self.on_poster = on_poster
        self.services, self.tasks = scopes(interface)
        self.scope: Scope | None = None
        self.locals: dict[str, Any] | None = None
        self.failure: dict[str, Any] | None = None
        self.calls = 0
        self.call: CodelCall | None = None  # the codel the engine thread is calling (the watchdog reads it)
        self.replay: dict[str, CodelCall] = {}  # extern -> a detached call whose step is fired again
        self.missing: list[str] = []
        self.times: CodelTimes | None = None  # set: every call's CPU and wall time is recorded there
        # (component, remote) -> the handle a ``remote`` argument gets (runtime.controller.remote)
        self.remotes: Callable[[str, str], Any] | None = None
        self._externs: dict[str, Callable[[], int]] | None = None
        # extern name -> (component, argument list) found anywhere: for a codel called outside its own scope
        self._anywhere: dict[str, tuple[str, list[Arg]]] = {}
        self._home: dict[str, str] = {}  # extern name -> the first service or task that has it, ``Module.Owner``
        self._fits: dict[tuple[str, str], Callable[[Any], bool]] = {}  # (component, port) -> its poster's test
        for scope in list(self.services.values()) + list(self.tasks.values()):
            for extern, args in scope.codels.items():
                self._anywhere.setdefault(extern, (scope.component, args))
                self._home.setdefault(extern, scope.label)

    def externs(self) -> dict[str, Callable[[], int]]:
        """One callable per codel extern of the model (made once)."""
        if self._externs is not None:
            return self._externs
        out = self._externs = {}
        for extern, spec in self.specs.items():
            component = self._anywhere.get(extern, (extern.split("_", 1)[0], []))[0]
            fn = self.source.find(component, spec.codel)
            if fn is None:
                self.missing.append(f"{component}.{spec.codel}")
                out[extern] = self._missing(spec, self.source.why_missing(component, spec.codel))
            else:
                out[extern] = self._caller(extern, spec, component, fn)
        return out

    def _missing(self, spec: CodelSpec, why: str) -> Callable[[], int]:
        def call() -> int:
            self.calls += 1
            self.failure = {"codel": spec.codel, "error": "missing codel", "message": why}
            return UNDECLARED
        return call

    @property
    def running(self) -> str | None:
        """The codel the engine thread is calling (to say what a stop interrupted)."""
        call = self.call
        return call.codel if call is not None and not call.done and not call.detached else None

    def _caller(self, extern: str, spec: CodelSpec, component: str, fn: Callable) -> Callable[[], int]:
        """The extern calling ``fn``: its arguments built, the call recorded for the watchdog, the outcome mapped."""
        def call() -> int:
            self.calls += 1
            replayed = self.replay.pop(extern, None)
            if replayed is not None:
                return self._conclude(spec, replayed)
            scope = self.scope
            args = scope.codels.get(extern) if scope is not None else None
            comp = scope.component if scope is not None and args is not None else component
            if args is None:
                args = self._anywhere.get(extern, (component, []))[1]
            kwargs, holders = self._arguments(comp, args)
            record = CodelCall(spec.codel, extern, comp, scope, self.locals, holders, time.monotonic(),
                               threading.current_thread(), time.thread_time())
            self.call = record
            try:
                outcome: tuple[str, Any] = ("return", fn(**kwargs))
            except BaseException as err:  # noqa: BLE001 - the codel's bug (even SystemExit), reported with its name
                outcome = ("raise", err)
            times = self.times
            if times is not None:  # in the codel's own thread, detached or not: its thread time is its own
                cpu, wall = time.thread_time() - record.cpu_started, time.monotonic() - record.started
                owner = scope.label if scope is not None and extern in scope.codels else self._home.get(extern, comp)
                times.record(f"{owner}.{spec.codel}", cpu, wall)
            if not record.finish(outcome):
                raise CodelDetached(record)  # the engine went on in another thread: the outcome waits there
            return self._conclude(spec, record)

        call.__name__ = spec.codel
        return call

    def _conclude(self, spec: CodelSpec, record: CodelCall) -> int:
        """The outcome index of a call that ended (or was given up on), its outputs stored; failures named."""
        if record.abandoned is not None:
            self.failure = {"codel": spec.codel, "error": "abandoned", "message": record.abandoned}
            return UNDECLARED
        how, value = record.outcome if record.outcome is not None else ("return", None)
        if how == "raise":
            if isinstance(value, Throw):
                if not self._write_back(record, spec):
                    return UNDECLARED
                return self._thrown(spec, value)
            if isinstance(value, CodelInterrupted):
                self.failure = {"codel": spec.codel, "error": "interrupted",
                                "message": f"codel {spec.codel} did not return after the controller was told to "
                                           "stop: interrupted"}
                return UNDECLARED
            frame = traceback.extract_tb(value.__traceback__)[-1]
            self.failure = {
                "codel": spec.codel,
                "error": "python exception",
                "message": f"codel {spec.codel} raised {type(value).__name__}" + (f": {value}" if str(value) else ""),
                "where": f"{frame.filename}:{frame.lineno}",
            }
            return UNDECLARED
        if not self._write_back(record, spec):
            return UNDECLARED
        if spec.yields == ("ok",) and value in (None, "ok"):
            return 0
        if isinstance(value, str) and value in spec.yields:
            return spec.yields.index(value)
        declared = ", ".join(spec.yields) or "nothing"
        self.failure = {"codel": spec.codel, "error": "undeclared yield",
                        "message": f"codel {spec.codel} returned {value!r}, not a declared yield "
                                   f"(declared: {declared})"}
        return UNDECLARED

    def _thrown(self, spec: CodelSpec, thrown: Throw) -> int:
        name = thrown.name
        match = next((t for t in spec.throws if t == name or t.endswith("::" + name.split("::")[-1])), None)
        if match is None:
            declared = ", ".join(spec.throws) or "none"
            self.failure = {"codel": spec.codel, "error": "undeclared exception", "exception": name,
                            "detail": thrown.detail,
                            "message": f"codel {spec.codel} threw {name}, which is not declared (declared: {declared})"}
            return UNDECLARED
        self.failure = {"codel": spec.codel, "exception": match, "detail": thrown.detail,
                        "message": f"codel {spec.codel} threw {match}"}
        return len(spec.yields) + spec.throws.index(match)

    # -- arguments --------------------------------------------------------------------------------
    def _arguments(self, component: str, args: list[Arg]) -> tuple[dict[str, Any], list[tuple[Arg, Ref]]]:
        kwargs: dict[str, Any] = {}
        holders: list[tuple[Arg, Ref]] = []
        ids = self.data.ids[component]
        for a in args:
            if a.source == "port":
                if a.direction == "in":
                    kwargs[a.name] = self.data.read_input(component, a.port)
                else:
                    ref = Ref(clone(self.data.poster(component, a.port).value))
                    kwargs[a.name] = ref
                    holders.append((a, ref))
                continue
            if a.source == "ids":
                value = get_path(ids, a.steps)
            elif a.source == "local":
                value = get_path(self.locals, a.steps) if self.locals is not None else None
            else:  # remote: a handle whose call is a request to the component that serves it
                kwargs[a.name] = self.remotes(component, a.port) if self.remotes is not None else None
                continue
            if a.direction == "in":
                kwargs[a.name] = clone(value)
            else:
                ref = Ref(clone(value))
                kwargs[a.name] = ref
                holders.append((a, ref))
        return kwargs, holders

    def _poster_problems(self, component: str, port: str, value: Any) -> list[str]:
        """What in ``value`` does not fit the IDL type of ``component``'s ``port out``, each with its path."""
        spec = self.interface["components"][component]["ports"].get(port)
        if spec is None or spec.get("multiple"):  # a multiple port's value is the codel's own dict of values
            return []
        schema, types = spec["schema"], self.interface.get("types", {})
        fits = self._fits.get((component, port))
        if fits is None:
            fits = self._fits[(component, port)] = checker(schema, types)
        return [] if fits(value) else problems(value, schema, types, port)

    def _write_back(self, record: CodelCall, spec: CodelSpec) -> bool:
        """Store what the codel left in its holders; False (and a failure) when a value has nowhere to go."""
        component, local = record.component, record.locals
        for a, ref in record.holders:
            try:
                if a.source == "port":
                    if ref.value is not None:
                        wrong = self._poster_problems(component, a.port, ref.value)
                        if wrong:
                            self.failure = {"codel": spec.codel, "error": "bad poster value", "port": a.port,
                                            "message": f"codel {spec.codel} wrote poster {component}.{a.port} "
                                                       f"(argument {a.name}): " + "; ".join(wrong[:5])}
                            return False
                        written = self.data.write_poster(component, a.port, ref.value)
                        if self.on_poster is not None:
                            self.on_poster(component, a.port, written)
                elif a.source == "ids":
                    set_path(self.data.ids[component], a.steps, ref.value)
                elif local is not None:
                    set_path(local, a.steps, ref.value)
            except (KeyError, IndexError, TypeError) as err:
                self.failure = {"codel": spec.codel, "error": "bad output",
                                "message": f"codel {spec.codel}: cannot store argument {a.name} "
                                           f"({a.source} {'.'.join(map(str, a.steps))}): {type(err).__name__}: {err}"}
                return False
        return True
