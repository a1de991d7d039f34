"""A campaign's jobs: every check of the file, on every model it names, at every point of its axes' cross product,
once per target (a property, an observer); each with a stable id, so that a result already written is recognised.

The targets are named on each model's first point, built here (its errors
located in the campaign file) before any job runs.
"""
from __future__ import annotations

import hashlib
import itertools
import json
import math
from dataclasses import dataclass, field, replace
from typing import Any

from genom2bip.campaign.kinds import KINDS, RESPONSE_OWNERS, TargetError
from genom2bip.campaign.params import ModelParams
from genom2bip.campaign.spec import Axis, Campaign, CheckSpec, ModelSpec
from runtime.diagnostics import DiagnosticError, Reporter, Span
from runtime.errors import Genom2bipError


@dataclass(frozen=True)
class Job:
    """One check of one target on one model at one point: everything a worker needs, in plain data."""

    id: str
    model: str  # the model's name in the file
    params: ModelParams
    check: str  # a kind of genom2bip.campaign.kinds.KINDS
    method: str
    target: str  # the property's name, the observer's path, "deadlock freedom"
    files: tuple[str, ...] = ()  # property files
    options: tuple[tuple[str, Any], ...] = ()  # SearchOptions keyword arguments
    point: tuple[tuple[str, Any], ...] = ()  # axis -> value as written in the file
    index: int = 0  # the job's place in the campaign (the order of the summary)
    timeout: float | None = None  # seconds of wall clock before the job is stopped (not part of its id)
    of: tuple[str, ...] = ()  # response times: whose are recorded (tasks, services); () all
    only: tuple[str, ...] | None = None  # response times: the owners recorded; None all
    smc: tuple[tuple[str, Any], ...] = ()  # statistical model checking: SmcSettings fields

    @property
    def title(self) -> str:
        where = " ".join(f"{k}={v}" for k, v in self.point)
        how = f" ({self.method})" if self.method != "explore" else ""
        return f"{self.model} {self.check} {self.target}{how}" + (f" [{where}]" if where else "")

    def parameters(self) -> dict[str, Any]:
        """What the results file says of the job: the model, the check, the point."""
        return {"model": self.model, "check": self.check, "method": self.method, "target": self.target,
                "point": dict(self.point), "options": dict(self.options), "timeout": self.timeout,
                **self.selection()}

    def selection(self) -> dict[str, Any]:
        """What a response-time job records (``of``, ``only``), where the file narrows it."""
        out: dict[str, Any] = {}
        if self.of:
            out["of"] = list(self.of)
        if self.only is not None:
            out["only"] = list(self.only)
        if self.smc:
            out["smc"] = dict(self.smc)
        return out


@dataclass
class Expansion:
    """The jobs, in the file's order, and the models built to name their targets (by parameters)."""

    jobs: list[Job] = field(default_factory=list)
    built: dict[ModelParams, Any] = field(default_factory=dict)
    warnings: list = field(default_factory=list)  # Diagnostic: a check with nothing to check


def job_id(base, params: ModelParams, check: str, method: str, target: str, files, options,
           selection: dict[str, Any] | None = None) -> str:
    """A hash of what decides the job's answer and what it records (not the names given in the file, nor its
    place)."""
    import os

    data = {"model": params.identity(base), "check": check, "method": method, "target": target,
            "files": [os.path.relpath(f, base) for f in files], "options": sorted(options), **(selection or {})}
    return hashlib.sha256(json.dumps(data, sort_keys=True, default=str).encode()).hexdigest()[:16]


def points(axes: list[Axis]) -> list[tuple[tuple[Axis, Any, Any], ...]]:
    """The cross product of the axes' values: each point a tuple of (axis, value as written, value read)."""
    return list(itertools.product(*[[(a, v, p) for v, p in zip(a.values, a.parsed)] for a in axes]))


#: Jobs of one campaign: past this many a note says how many (a job takes seconds to hours: 10,000 is days of work).
WARN_JOBS = 10_000
#: Jobs of one campaign at most: counted before any is made (a million jobs took 1.4 GB and 4 minutes to list).
MAX_JOBS = 100_000


def _too_many(planned: int, check: CheckSpec, reporter: Reporter) -> bool:
    """Report (at the check's axes) a campaign of more than MAX_JOBS jobs; True when it is."""
    if planned <= MAX_JOBS:
        return False
    reporter.error(check.axes[0].span if check.axes else check.span,
                   f"the campaign makes at least {planned:,} jobs (the cross product of the axes' values, for each "
                   f"model and target), more than the {MAX_JOBS:,} a campaign may hold",
                   "fewer values per axis, or several campaigns")
    return True


def expand(campaign: Campaign, reporter: Reporter | None = None) -> Expansion:
    """Every job of the campaign; raises DiagnosticError (located in the campaign file) for a model that does not
    build on its first point or targets that cannot be named."""
    reporter = reporter or Reporter()
    out = Expansion()
    seen: set[str] = set()
    planned = 0  # jobs counted so far, before they are made
    for check in campaign.checks:
        kind = KINDS[check.kind]
        per_model = math.prod(len(a.values) for a in check.axes)
        if _too_many(planned + per_model * len(campaign.models[check.model]), check, reporter):
            reporter.raise_if_errors()
        for spec in campaign.models[check.model]:
            grid = points(check.axes)
            base = kind.params(spec.params) if kind.params else spec.params
            first = _at(base, grid[0])
            model = _build(out, first, spec, check, reporter)
            if model is None:
                continue
            try:
                targets = kind.targets(check, lambda: model)
            except TargetError as exc:
                reporter.error(check.spans.get(exc.key, check.span), f"check {check.kind} on {spec.name}: {exc}")
                continue
            except DiagnosticError as exc:  # a property file's own errors
                reporter.diagnostics.extend(exc.diagnostics)
                continue
            if not targets:
                reporter.warning(check.span, f"check {check.kind} on {spec.name}: nothing to check")
            planned += len(grid) * len(targets)
            if _too_many(planned, check, reporter):
                reporter.raise_if_errors()
            for point in grid:
                params = _at(base, point)
                for target in targets:
                    name, files = kind.name, tuple(check.files)
                    if isinstance(target, tuple):  # another kind's job answers it
                        (name, target), files = target, ()
                    options = tuple(sorted(check.options.items()))
                    job = Job("", spec.name, params, name, check.method, target, files, options,
                              tuple((a.key, v) for a, v, _ in point), len(out.jobs), check.timeout,
                              *_selection(check, name), check.smc if name == "smc" else ())
                    jid = job_id(campaign.base, params, name, check.method, target, files, options, job.selection())
                    if jid in seen:
                        continue  # the same job twice (two checks overlap): run once
                    seen.add(jid)
                    out.jobs.append(replace(job, id=jid))
    reporter.raise_if_errors()
    if len(out.jobs) > WARN_JOBS:
        reporter.warning(Span(str(campaign.path), 0, 0), f"{len(out.jobs):,} jobs: a large campaign (each job takes "
                                                         "seconds to hours); --list shows them")
    out.warnings = [d for d in reporter.diagnostics if d.severity == "warning"]
    return out


def _selection(check: CheckSpec, kind: str) -> tuple[tuple[str, ...], tuple[str, ...] | None]:
    """``(of, only)`` of a response-time job: () and None where the file keeps them all."""
    if kind != "response-times":
        return (), None
    of = () if set(check.of) == set(RESPONSE_OWNERS) else tuple(check.of)
    return of, tuple(check.only) if check.only is not None else None


def _at(params: ModelParams, point) -> ModelParams:
    for axis, _, value in point:
        params = axis.kind.apply(params, axis.name, value)
    return params


def _build(out: Expansion, params: ModelParams, spec: ModelSpec, check: CheckSpec, reporter: Reporter):
    """The model of ``params`` (built once); its problems reported where the file names the model or the axis."""
    from genom2bip.generate import GenerateError
    from genom2bip.loading import InputError

    if params in out.built:
        return out.built[params]
    model = None
    try:
        model = params.build()
        model.flat  # noqa: B018 - the engine's own refusal, here rather than in every job
    except DiagnosticError as exc:  # the descriptions' own file:line:column
        reporter.diagnostics.extend(exc.diagnostics)
    except InputError as exc:
        for message in exc.messages:
            reporter.error(_where(message, spec, check), f"model {spec.name}: {message}")
        for group in exc.groups:
            reporter.diagnostics.extend(group.diagnostics)
    except (GenerateError, Genom2bipError) as exc:
        reporter.error(spec.span, f"model {spec.name}: {exc}")
    out.built[params] = model
    return model


def _where(message: str, spec: ModelSpec, check: CheckSpec) -> Span:
    """An axis's problem (a period of a task that is not there) at the axis; the others at the model."""
    for axis in check.axes:
        if axis.kind.name == "period" and message.startswith(f"period of {axis.name}:"):
            return axis.span
    return spec.span
