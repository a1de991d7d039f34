"""Extern functions during exploration: codels become choice points, the environment may send any request.

The engine's compiled ``fire`` is pure apart from its extern calls.  The
explorer binds every codel extern to an :class:`Oracle` that answers from a
script of pre-decided outcomes and records each call with its domain; running
``fire`` again with the next script (an odometer over the calls made) visits
every combination of outcomes exactly once (:func:`outcome_vectors`).  Nothing
about BIP semantics is re-implemented: branching happens where execution would
call the codel.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Iterator

from runtime.codels import UNDECLARED, codel_specs
from runtime.engine.errors import EngineError
from runtime.model import Package

#: Externs the generated acceptor calls; the exploration environment answers them (see :class:`Environment`).
REQUEST_EXTERNS = ("request_pending", "take_request")


class ExploreError(EngineError):
    """The model cannot be explored as asked: an unbound extern, a choice in a guard, a bad option."""


@dataclass(frozen=True)
class Choice:
    """An extern whose value the explorer chooses among ``values`` (a codel, or one a user declares finite)."""

    name: str
    values: tuple[Any, ...]
    names: tuple[str, ...] = ()

    def describe(self, position: int) -> str:
        """``nddPlan -> arrived``: the outcome at ``position`` of the domain, as a trace shows it."""
        label = self.names[position] if position < len(self.names) else repr(self.values[position])
        return f"{self.name} -> {label}"


def codel_choices(package: Package) -> dict[str, Choice]:
    """One :class:`Choice` per codel extern: its yields, then its exceptions (docs/engine.md).

    A codel that declares no outcome at all can only fail: its domain is the
    undeclared outcome, which the activity treats as a failure.
    """
    out = {}
    for name, spec in codel_specs(package).items():
        n = len(spec.outcomes)
        values = tuple(range(n)) if n else (UNDECLARED,)
        names = spec.outcomes if n else ("undeclared failure",)
        out[name] = Choice(spec.codel, values, names)
    return out


class Oracle:
    """Answers the choice externs during one run of ``fire`` (or ``initial``) from a script, and records the calls.

    ``calls`` holds ``(choice, position)`` for each call made; ``script`` the
    positions to answer (0 past its end).  A choice extern called while
    ``enabled`` evaluates guards is noted in ``guard_call`` (the explorer
    refuses the model: exploration branches in actions only).
    """

    def __init__(self) -> None:
        self.script: list[int] = []
        self.calls: list[tuple[Choice, int]] = []
        self.in_guard = False
        self.guard_call: str | None = None

    def bind(self, choice: Choice) -> Callable[..., Any]:
        calls = self.calls
        script = self.script

        def answer(*_args):
            if self.in_guard:
                self.guard_call = choice.name
                return choice.values[0]
            k = len(calls)
            pos = script[k] if k < len(script) else 0
            calls.append((choice, pos))
            return choice.values[pos]

        answer.__name__ = choice.name
        return answer

    def start(self, script: list[int] | tuple[int, ...] = ()) -> None:
        self.calls.clear()
        self.script[:] = script

    def next_script(self) -> list[int] | None:
        """The odometer: the script of the next combination of outcomes, or None after the last one."""
        calls = self.calls
        k = len(calls) - 1
        while k >= 0 and calls[k][1] + 1 >= len(calls[k][0].values):
            k -= 1
        if k < 0:
            return None
        return [pos for _, pos in calls[:k]] + [calls[k][1] + 1]

    def made(self) -> tuple[tuple[Choice, int], ...]:
        return tuple(self.calls)


def outcome_vectors(oracle: Oracle, run: Callable[[], Any]) -> Iterator[tuple[Any, tuple[tuple[Choice, int], ...]]]:
    """Every result of ``run()`` over all combinations of the choices it makes, with the choices made.

    ``run`` is re-executed once per combination; the number of calls may
    depend on earlier answers (an odometer over a tree, not a product).
    """
    oracle.start()
    while True:
        result = run()
        made = oracle.made()
        yield result, made
        nxt = oracle.next_script()
        if nxt is None:
            return
        oracle.start(nxt)


class Environment:
    """The services' clients during exploration: any request, at any time the acceptor takes one.

    Without a budget, ``request_pending`` always holds, so the only bound is
    the model's own: a service takes one request at a time.  With
    ``budget=N`` each service receives at most N requests over a run; the
    count of requests taken so far per service becomes part of the state.
    """

    def __init__(self, budget: int | None = None) -> None:
        if budget is not None and budget < 0:
            raise ExploreError("the request budget must be >= 0")
        self.budget = budget
        self.services: dict[str, int] = {}
        self.current: tuple[int, ...] = ()
        self.taken: list[str] = []

    @property
    def tracked(self) -> bool:
        return self.budget is not None

    def slot(self, service: str) -> int:
        k = self.services.get(service)
        if k is None:
            raise ExploreError(f"request for unknown service {service!r} (known: {', '.join(self.services)})")
        return k

    def externs(self) -> dict[str, Callable]:
        if self.budget is None:
            return {"request_pending": lambda service: True, "take_request": lambda service: None}

        def pending(service):
            return self.current[self.slot(service)] < self.budget

        def take(service):
            self.taken.append(service)

        return {"request_pending": pending, "take_request": take}

    def after(self, counts: tuple[int, ...]) -> tuple[int, ...]:
        """The counts once the requests taken during the last ``fire`` are added."""
        if not self.taken:
            return counts
        out = list(counts)
        for service in self.taken:
            out[self.slot(service)] += 1
        self.taken.clear()
        return tuple(out)


def request_services(package: Package) -> list[str]:
    """Services named by constant string arguments of ``request_pending`` in the model's guards, in order."""
    from runtime.model.expressions import Binary, Call, Const, Unary

    found: list[str] = []

    def walk(e) -> None:
        if isinstance(e, Call):
            if e.function in REQUEST_EXTERNS and e.args and isinstance(e.args[0], Const):
                if e.args[0].value not in found:
                    found.append(e.args[0].value)
            for a in e.args:
                walk(a)
        elif isinstance(e, Unary):
            walk(e.operand)
        elif isinstance(e, Binary):
            walk(e.left)
            walk(e.right)

    for t in package.atom_types:
        for tr in t.transitions:
            walk(tr.guard)
    return found


def bind_for_exploration(package: Package, user: dict[str, Any] | None, oracle: Oracle,
                         environment: Environment) -> dict[str, Callable]:
    """Extern bindings for the explorer: user bindings first, then codel choices, then the environment.

    A user binding that is a :class:`Choice` becomes a choice point too.  An
    extern left unbound makes the engine refuse the model if it is called
    (see :func:`unbound_message`): the explorer cannot guess what it returns.
    """
    user = dict(user or {})
    choices = codel_choices(package)
    bound: dict[str, Callable] = {}
    env = environment.externs()
    for name in sorted(f.name for f in package.extern_functions):
        given = user.get(name)
        if isinstance(given, Choice):
            bound[name] = oracle.bind(given)
        elif given is not None:
            if not callable(given):
                raise ExploreError(f"extern {name}: binding is not callable")
            bound[name] = given
        elif name in choices:
            bound[name] = oracle.bind(choices[name])
        elif name in env:
            bound[name] = env[name]
    return bound


def unbound_message(missing: tuple[str, ...] | list[str]) -> str:
    return (f"extern function(s) {', '.join(missing)} are neither codels (no @codel annotation giving their "
            "outcomes) nor the request externs: the explorer cannot tell what they return; bind them to Python "
            "functions (--externs MODULE) or declare them with @codel(yields=...)")
