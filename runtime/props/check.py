"""Reading property files against a model, and checking each property on the fly with evidence.

``read_properties`` parses, types and statically checks a file (every problem
with ``file:line:column``), binds state predicates to the model and refuses
labels no interaction has (unless written ``optional``).  ``check`` answers one property on a
:class:`~runtime.explore.space.StateSpace`: safety shapes ``[R] F`` / ``<R> F``
(F without fixed points) by a breadth-first product search with shortest
traces, anything else by the local fixed-point solver.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

from runtime.diagnostics import Diagnostic, DiagnosticError, SourceCache
from runtime.engine.errors import EngineError
from runtime.engine.flatten import FlatSystem
from runtime.explore.space import LimitReached, StateSpace, Step
from runtime.props.actions import label_matcher, leaves, matcher
from runtime.props.formulas import (
    ALabel,
    Pred,
    Property,
    RAct,
    RAlt,
    Regular,
    RPlus,
    RSeq,
    RStar,
    SAnd,
    SBox,
    SDia,
    SFix,
    SImplies,
    SNot,
    SOr,
    SPred,
    State,
    show,
)
from runtime.props.normal import compile_formula, normalize, positive
from runtime.props.predicates import bind, variables_read
from runtime.props.safety import automaton, search
from runtime.props.solver import Solver
from runtime.props.syntax import parse_properties
from runtime.props.typing import type_properties
from runtime.textfile import read_text


@dataclass
class Checkable:
    """A property ready to check: its normal form, bound predicates, and what it reads of the state."""

    property: Property
    normal: State
    observed: set[tuple[str, str]] = field(default_factory=set)

    @property
    def name(self) -> str:
        return self.property.name


@dataclass
class Verdict:
    """``holds`` is True, False, or None when the state budget ran out before an answer."""

    property: Property
    holds: bool | None
    trace: list[Step] = field(default_factory=list)
    evidence: str = ""  # "witness", "counterexample" or ""
    loop: int = -1  # index of the step the trace loops back to, or -1
    method: str = ""
    states: int = 0
    seconds: float = 0.0
    note: str = ""
    error: str = ""  # a model error met while checking (the verdict is then None)

    @property
    def word(self) -> str:
        if self.error:
            return "model error"
        return {True: "holds", False: "violated", None: "inconclusive"}[self.holds]


# --- reading ------------------------------------------------------------------------------------------

def _regulars(r: Regular):
    if isinstance(r, RAct):
        yield r.action
    elif isinstance(r, (RSeq, RAlt)):
        yield from _regulars(r.left)
        yield from _regulars(r.right)
    elif isinstance(r, (RStar, RPlus)):
        yield from _regulars(r.operand)


def _actions(f: State):
    if isinstance(f, (SDia, SBox)):
        yield from _regulars(f.path)
        yield from _actions(f.operand)
    elif isinstance(f, (SAnd, SOr, SImplies)):
        yield from _actions(f.left)
        yield from _actions(f.right)
    elif isinstance(f, SNot):
        yield from _actions(f.operand)
    elif isinstance(f, SFix):
        yield from _actions(f.body)


def _preds(f: State):
    if isinstance(f, SPred):
        yield f.pred
    elif isinstance(f, (SDia, SBox)):
        yield from _preds(f.operand)
    elif isinstance(f, (SAnd, SOr, SImplies)):
        yield from _preds(f.left)
        yield from _preds(f.right)
    elif isinstance(f, SNot):
        yield from _preds(f.operand)
    elif isinstance(f, SFix):
        yield from _preds(f.body)


def model_labels(flat: FlatSystem) -> list[str]:
    """The labels interactions of the model can carry (connector labels and lone ports)."""
    out = [fc.label for fc in flat.connectors if fc.top]
    out += [fp.path for fp in flat.ports if not fp.decl.exported]
    return out


def read_properties(text: str, file: str, flat: FlatSystem | None = None) -> tuple[list[Checkable], list[Diagnostic]]:
    """Parse and check a property file; returns the properties and the warnings, or raises DiagnosticError."""
    sources = SourceCache()
    sources.add(file, text)
    problems: list[Diagnostic] = []
    typed = type_properties(parse_properties(text, file), problems,
                            (lambda service: cancel_labels(flat, service)) if flat is not None else None)
    out = []
    labels = model_labels(flat) if flat is not None else []
    for prop in typed:
        normal = normalize(prop.formula, problems) if not any(d.severity == "error" for d in problems) else None
        observed: set[tuple[str, str]] = set()
        if flat is not None:
            for p in _preds(prop.formula):
                bind(flat, p, problems)
                observed |= variables_read(flat, p)
            for a in _actions(prop.formula):
                problems.extend(_unmatched(a, labels))
        out.append(Checkable(prop, normal, observed))
    errors = [d for d in problems if d.severity == "error"]
    if errors:
        unique = []
        for d in sorted(problems, key=lambda d: (d.span.line, d.span.column)):
            if d not in unique:
                unique.append(d)
        raise DiagnosticError(unique, sources)
    return out, [d for d in problems if d.severity == "warning"]


def cancel_labels(flat: FlatSystem, service: str) -> list[str] | None:
    """The labels of the interactions that cancel a request of ``service`` (``M.S``) before it starts: the starts
    of the services that interrupt it (their connector takes its controller's ``cancel``).  None when the model
    has no controller for it."""
    control = f"{service}.control"
    if not any(a.name == control for a in flat.atoms):
        return None
    port = f"{control}.cancel"
    out = []
    for fc in flat.connectors:
        if fc.top and fc.label and fc.label not in out and any(flat.ports[p].path == port for p in flat.leaves(fc)):
            out.append(fc.label)
    return sorted(out)


def _unmatched(a, labels: list[str]) -> list[Diagnostic]:
    """An error for each label or pattern of ``a`` that no label of the model matches, unless it is ``optional``.

    A misspelt label would otherwise make ``[ ... "NDD.Fly:start" ] false`` hold without saying anything.
    """
    out = []
    for leaf in leaves(a):
        if leaf.optional or not labels:
            continue
        m = label_matcher(leaf.text) if isinstance(leaf, ALabel) else matcher(leaf)
        if not any(m(lab) for lab in labels):
            text = f'"{leaf.text}"' if isinstance(leaf, ALabel) else f"'{leaf.pattern}'"
            out.append(Diagnostic(leaf.span, f"{text} matches no interaction label of the model", "error",
                                  _label_hint(leaf, labels, text)))
    return out


def _label_hint(leaf, labels: list[str], text: str) -> str:
    """The nearest labels of the model, and how to say that matching nothing is intended."""
    import difflib

    word = leaf.text if isinstance(leaf, ALabel) else leaf.pattern
    near = difflib.get_close_matches(word, labels, n=3, cutoff=0.5)
    if not near:  # the paper's writing, without the module: compare with the labels' tails
        tails = {lab.partition(".")[2]: lab for lab in labels if "." in lab}
        near = [tails[t] for t in difflib.get_close_matches(word, list(tails), n=3, cutoff=0.5)]
    if not near:
        near = difflib.get_close_matches(word, labels, n=3, cutoff=0.0)
    known = ", ".join(f'"{lab}"' for lab in near)
    lead = f"did you mean {known}?" if len(near) == 1 else f"nearest labels: {known}."
    return f"{lead} If matching nothing is intended, write optional {text}"


def read_property_file(path: str | Path, flat: FlatSystem | None = None) -> tuple[list[Checkable], list[Diagnostic]]:
    text = read_text(path, "property file")
    return read_properties(text, str(path), flat)


def read_property_text(text: str, flat: FlatSystem | None = None) -> Checkable:
    """One property from a string (for the API and tests)."""
    props, _ = read_properties(text, "<property>", flat)
    return props[0]


# --- checking -----------------------------------------------------------------------------------------

def _bound(space: StateSpace, preds: list[Pred]):
    problems: list[Diagnostic] = []
    out = [bind(space.engine.flat, p, problems) for p in preds]
    if problems:
        raise DiagnosticError(problems)
    return out


def _solver(space: StateSpace, f: State) -> Solver:
    eq = compile_formula(f)
    return Solver(eq, space, _bound(space, eq.preds))


def check(space: StateSpace, item: Checkable, progress=None) -> Verdict:
    """Check one property from the initial state(s); never raises on a limit (the verdict is then None)."""
    start = time.perf_counter()
    prop = item.property
    top = positive(prop.formula)
    try:
        verdict = _safety(space, item, top, progress)
        if verdict is None:
            verdict = _general(space, item)
    except LimitReached:
        verdict = Verdict(prop, None, note=f"the state budget ({space.max_states:,} states) ran out before an answer",
                          method="")
    except EngineError as err:  # non-determinism, 1-safety, a domain left...: the model is wrong before the property
        verdict = Verdict(prop, None, note=str(err), error=str(err))
    verdict.states = len(space)
    verdict.seconds = time.perf_counter() - start
    return verdict


def _safety(space: StateSpace, item: Checkable, top: State, progress) -> Verdict | None:
    """``[R] F`` / ``<R> F`` with a fixed-point-free F: product search, shortest path."""
    if not isinstance(top, (SBox, SDia)):
        return None
    problems: list[Diagnostic] = []
    inner = normalize(top.operand, problems)
    local = _solver(space, inner)
    if not local.eq.local(0):
        return None
    box = isinstance(top, SBox)
    auto = automaton(top.path)

    def found(sid: int) -> bool:
        return local.value(sid * local.n) != box

    hit = search(space, auto, found, progress)
    prop = item.property
    if hit is None:
        if box:
            return Verdict(prop, True, method="safety search")
        return Verdict(prop, False, method="safety search",
                       note="no path matching the regular formula reaches a state where the rest holds")
    states, labels = hit.states, hit.labels
    more = local.evidence(states[-1] * local.n)
    states = states + more.states[1:]
    labels = labels + more.labels
    trace = _steps(space, states, labels)
    return Verdict(prop, not box, trace, "counterexample" if box else "witness", method="safety search")


def _general(space: StateSpace, item: Checkable) -> Verdict:
    """The local fixed-point solver; a path is shown only where one path is the evidence.

    A least fixed point that holds, or a greatest one that fails, is shown by a
    path (its derivation); a greatest fixed point that holds or a least one
    that fails is a statement about every path, which no single path shows.
    """
    solver = _solver(space, item.normal)
    prop = item.property
    eq = solver.eq
    universal_true = eq.sign[0] == "nu" and eq.block[0] != -1
    universal_false = eq.sign[0] == "mu" and eq.block[0] != -1
    for sid in space.initial_ids:
        key = sid * solver.n
        if not solver.value(key):
            if universal_false:
                return Verdict(prop, False, method="local fixed point",
                               note="no path satisfies the least fixed point")
            ev = solver.evidence(key)
            return Verdict(prop, False, _steps(space, ev.states, ev.labels), "counterexample", ev.loop,
                           "local fixed point")
    if universal_true:
        return Verdict(prop, True, method="local fixed point")
    ev = solver.evidence(space.initial_ids[0] * solver.n)
    trace = _steps(space, ev.states, ev.labels)
    return Verdict(prop, True, trace, "witness" if trace else "", ev.loop, "local fixed point")


def _steps(space: StateSpace, states: list[int], labels: list[int]) -> list[Step]:
    return space.steps_along(states, [space.labels[k] for k in labels])


def describe(item: Checkable) -> str:
    """``name: text as written`` (and what a shorthand means)."""
    p = item.property
    text = p.text or show(p.formula)
    if p.pattern:
        return f"{p.name}: {text}\n  means: {p.meaning or show(p.formula)}"
    return f"{p.name}: {text}"


__all__ = ["Checkable", "Verdict", "check", "describe", "read_properties", "read_property_file",
           "read_property_text"]

