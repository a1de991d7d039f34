"""What a campaign can check: one entry per kind of check, each naming its jobs and running one through the
verification API.

A check of the file (``check: property``, ``files: [...]``) becomes one job
per target: per property of its files, per observer of its timed model, one
for deadlock freedom.  A new kind (response times: a value per task) is one
more :class:`CheckKind` in :data:`KINDS`: its keys, how it names its targets,
how a job runs, and (for pictures) the figures its result gives.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, Callable

from genom2bip.campaign.params import ModelParams

if TYPE_CHECKING:
    from genom2bip.verify import CheckResult, Model, SearchOptions

#: How a check is decided, in ``verify``'s words: the explorer, or (``compositional``) deadlock freedom by
#: invariants and SAT, properties and observers by localization.
METHODS = ("explore", "compositional")


class TargetError(ValueError):
    """A check's targets cannot be named: ``key`` is the key of the check at fault."""

    def __init__(self, key: str, message: str) -> None:
        super().__init__(message)
        self.key = key


@dataclass(frozen=True)
class CheckKind:
    """A kind of check: its own keys in the file, its targets, how one job runs, what figures its result gives."""

    name: str
    help: str
    keys: tuple[str, ...]  # besides check, model, method, options, vary
    required: tuple[str, ...]
    # the targets, each a name, or (kind, name) for a job of another kind that answers it
    # (a check of the file: genom2bip.campaign.spec.CheckSpec, its model on the first point) -> targets
    targets: Callable[[Any, Callable[[], "Model"]], list[str | tuple[str, str]]]
    run: Callable[["Model", Any, "SearchOptions"], "CheckResult"]
    timed: bool = False  # needs a timed model
    # numbers a result gives besides states and seconds (a response time per task): a record's ``values``, plotted;
    # a value that is a word (``unbounded``) is recorded as such and drawn apart from the numbers
    figures: Callable[["CheckResult", Any], dict[str, float | str]] | None = None  # (result, its job)
    # what the kind asks of its model's parameters (the response-time observers), before the axes
    params: Callable[[ModelParams], ModelParams] | None = None


# --------------------------------------------------------------------------- deadlock freedom


def _deadlock_targets(check, model) -> list[str]:
    return ["deadlock freedom"]


def _run_deadlock(model, job, options):
    from genom2bip.verify import check_deadlock, check_deadlock_compositional, spin_deadlock, state_space

    if job.method == "compositional":
        return check_deadlock_compositional(model, options)
    space = state_space(model, options)
    return spin_deadlock(space, options) if options.engine == "spin" else check_deadlock(space, options)


# --------------------------------------------------------------------------- properties


def _property_targets(check, model) -> list[str | tuple[str, str]]:
    """The properties of the check's files, in order (``only``: those named); the files' errors are raised."""
    from genom2bip.verify import read_properties

    items, _ = read_properties(model(), check.files)  # DiagnosticError: the property file's own file:line:column
    deadlock = {i.name for i in items if i.property.pattern == "deadlock free"}
    # compositionally, deadlock freedom is the invariants' (not localization's): the deadlock check's job
    return [("deadlock", "deadlock freedom") if check.method == "compositional" and n in deadlock else n
            for n in _only(check, [i.name for i in items], "property")]


def _run_property(model, job, options):
    """The job's property, read from its files against the model: by the explorer, SPIN or localization."""
    from genom2bip.verify import (
        check_property, check_property_localized, read_properties,
        refuse_unlocalizable, spin_property, state_space,
    )

    items, _ = read_properties(model, job.files)
    item = next((i for i in items if i.name == job.target), None)
    if item is None:
        raise LookupError(f"no property {job.target} in {', '.join(job.files)} for this model")
    if job.method == "compositional":
        refuse_unlocalizable([item])
        return check_property_localized(model, item, options)
    space = state_space(model, options, [item], keep_edges=True)
    return spin_property(space, item, options) if options.engine == "spin" else check_property(space, item, options)


# --------------------------------------------------------------------------- timing observers


def _observer_targets(check, model) -> list[str]:
    """The observers of the check's kinds in the timed model (``only``: those named), by instance path."""
    from genom2bip.verify import observers

    return _only(check, [a.path for a in observers(model(), check.kinds)], "observer")


def _run_observer(model, job, options):
    from genom2bip.verify import check_observer, check_observer_localized, observers

    atom = next((a for a in observers(model) if a.path == job.target), None)
    if atom is None:
        raise LookupError(f"no observer {job.target} in this model")
    if job.method == "compositional":
        return check_observer_localized(model, atom, options)
    if job.params.platform or job.params.cores:  # as verify does on a platform: clock zones, where they take it
        from genom2bip.verify.zones import ZonesUnsupported, check_timing

        try:
            return next(r for r in check_timing(model, (atom.kind,), options=options) if r.observer == atom.path)
        except ZonesUnsupported:
            pass
    return check_observer(model, atom, None, options)


# --------------------------------------------------------------------------- response times

#: ``of:`` of a response-time check: whose response times it records.
RESPONSE_OWNERS = ("tasks", "services")


def _response_targets(check, model) -> list[str]:
    """One job per model and point: one exploration gives every response time (``only``: owners that must be
    there, named now)."""
    from genom2bip.verify.zones import response_owners

    if check.method != "explore":
        raise TargetError("method", "response times are measured by one exploration with clock zones: "
                                    "method explore (the default)")
    if check.only is not None:
        _only(check, list(response_owners(model())), "task or service")
    return ["response times"]


def _run_responses(model, job, options):
    """The response times of the job's tasks and services (``of``, ``only``): its verdict is theirs."""
    from genom2bip.verify.zones import check_response_times

    wanted = {k[:-1] for k in (job.of or RESPONSE_OWNERS)}  # tasks -> task, services -> service
    return check_response_times(model, options,
                                owners=lambda r: r.kind in wanted and (job.only is None or r.owner in job.only))


def _response_figures(result, job) -> dict[str, float | str]:
    """Each recorded task's or service's response time: ms, or a word where there is none."""
    return result.values()


# --------------------------------------------------------------------------- statistical model checking


def _smc_targets(check, model) -> list[str]:
    """One job per model and point: one set of runs estimates every observer (``kinds``) and response time."""
    if check.method != "explore":
        raise TargetError("method", "statistical model checking runs the model: method explore (the default)")
    bound = dict(check.smc).get("horizon_us")
    return [f"Pr[<= {bound / 1000:g} ms]" if bound else "Pr[<= 1000 ms]"]


def _run_smc(model, job, options):
    """Estimate every observer of the job's kinds here, in the worker (docs/smc.md)."""
    from genom2bip.verify.smc import SmcSettings, estimate, summary

    fields = {"horizon_us": 1_000_000, **dict(job.smc)}
    fields["epsilon"], fields["delta"] = float(fields.get("epsilon", 0.01)), float(fields.get("delta", 0.05))
    report = estimate(model, SmcSettings(**fields))
    return summary(report, job.target)


def _only(check, names: list[str], what: str) -> list[str]:
    if check.only is None:
        return names
    missing = [n for n in check.only if n not in names]
    if missing:
        raise TargetError("only", f"no {what} {', '.join(missing)} (found: {', '.join(names) or 'none'})")
    return [n for n in names if n in check.only]


#: Every kind of check, by the name written in the file.
KINDS: dict[str, CheckKind] = {k.name: k for k in (
    CheckKind("deadlock", "deadlock freedom (a time-lock on a timed model)", (), (), _deadlock_targets,
              _run_deadlock),
    CheckKind("property", "each property of MCL-style files (files: [...], only: [names])", ("files", "only"),
              ("files",), _property_targets, _run_property),
    CheckKind("observer", "each timing observer of a timed model (kinds: [overrun, latency], only: [paths])",
              ("kinds", "only"), (), _observer_targets, _run_observer, timed=True),
    CheckKind("response-times", "every task's and service's largest response time, one job per point "
              "(of: [tasks, services], only: [owners])", ("of", "only"), (), _response_targets, _run_responses,
              timed=True, figures=_response_figures, params=lambda p: replace(p, responses=True)),
    CheckKind("smc", "statistical model checking: each timing observer's Pr[<= T] and the response-time "
              "distributions from random runs, one job per point (smc: {time-bound, epsilon, delta, threshold, "
              "runs, seed, proba})", ("smc",), (), _smc_targets, _run_smc, timed=True),
)}
