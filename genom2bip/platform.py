"""The computer a functional level runs on, in YAML: cores, a scheduling policy, execution times, task offsets.

A platform file (``verify --timed --platform FILE``)::

    cores: 2
    policy: edf                  # edf (cooperative EDF) or fixed-priority
    releases: together           # tasks released at one instant: together (default) or one-by-one
    best: 0 ms                   # best case of a codel the file does not list: a duration, or wcet
    execution:                   # [best, worst] per codel; a single duration is exact
      robloco.TrackSpeedStart.tssExec: [0 ms, 10 ms]
      robloco.odo.InitOdoParameters: [8 ms, 10 ms]
    tasks:
      robloco.track:
        delay: [8 ms, 10 ms]     # the first period opens this long after start (overrides 'delay')
        priority: 10             # fixed-priority: 0 is the highest (overrides 'priority')
      robmotion.plan:
        suspend: 11 ms           # after each release the task waits this long before it asks for a core
    distributions:               # statistical model checking only (docs/smc.md): how a duration is drawn
      robloco.TrackSpeedStart.tssExec: {triangular: 8 ms}   # default uniform; or {normal: [mean, sd]}

Codels are named ``Component.Owner.codel`` where the owner is the service or
task whose automaton runs the codel.  Every problem is reported with the file,
line and column of the value at fault, as in rule files; nothing is built.
``genom2bip.build.platform`` turns a :class:`Platform` into atoms, connectors
and priorities of the BIP model (docs/verification/platform.md, *The platform*).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from genom2bip import ir, rules
from genom2bip.durations import parse_duration
from genom2bip.rules import _suggest
from genom2bip.yamlfile import compose_file
from runtime.diagnostics import Reporter, Span
from runtime.smc.sampling import DISTRIBUTIONS, Distribution

POLICIES = ("edf", "fixed-priority")
#: How the tasks released at one instant meet the cores: all queued before a core is granted (one timer interrupt
#: wakes them all), or each release seen in turn, the first taking a free core before the next is queued.
RELEASES = ("together", "one-by-one")
#: When a task's suspension starts: at its release (it asks for a core after), or once its core is granted (it keeps
#: the core, idle, through the suspension: the RobNav artefact's delay in the manager of a task).
SUSPEND_AFTER = ("release", "grant")
SUSPEND_KEYS = ("for", "after")
KEYS = ("cores", "policy", "releases", "best", "execution", "tasks", "distributions")
TASK_KEYS = ("delay", "priority", "suspend")
#: More cores than this is a typing error, not a computer (each core is a value of the model's state).
MAX_CORES = 256
#: A codel's worst case or a task's delay past this many periods (of its task, else the longest one) is refused:
#: no task means it, and the search would follow every period of the others through it.  Past one period it is
#: accepted with a warning (an overrun that the check finds and reports).
MAX_PERIODS = 100
#: GenoM3 priorities go from 0 (highest) to 255 (lowest); a task without one is among the lowest.
LOWEST_PRIORITY = 255


@dataclass(frozen=True)
class Interval:
    """``[best, worst]`` in µs: a codel's execution time, or a task's first-period offset."""

    best_us: int
    worst_us: int

    def __str__(self) -> str:
        return f"[{self.best_us / 1000:g} ms, {self.worst_us / 1000:g} ms]"


@dataclass
class TaskSettings:
    delay: Interval | None = None
    priority: int | None = None
    suspend: Interval | None = None  # self-suspension after each release, before the task asks for a core
    suspend_after: str = "release"  # or "grant": the suspension comes once the core is granted, which it keeps


@dataclass
class Platform:
    """What a platform file says; absent keys keep the description's values."""

    cores: int
    policy: str = "edf"
    releases: str = "together"
    best: str | int = 0  # µs, or "wcet": the best case of a codel the file does not list
    execution: dict[tuple[str, str, str], Interval] = field(default_factory=dict)  # (component, owner, codel)
    tasks: dict[tuple[str, str], TaskSettings] = field(default_factory=dict)  # (component, task)
    path: str = ""
    # how statistical model checking draws a codel's duration in its interval (docs/smc.md); uniform when absent
    distributions: dict[tuple[str, str, str], Distribution] = field(default_factory=dict)

    def describe(self) -> str:
        """One line for reports: ``2 cores, cooperative EDF``."""
        if not self.path:
            return DEDICATED
        policy = "cooperative EDF" if self.policy == "edf" else "fixed priority (non-preemptive at codel boundaries)"
        releases = ", releases at one instant one by one" if self.releases == "one-by-one" else ""
        return f"{self.cores} core{'s' if self.cores != 1 else ''}, {policy}{releases}"


#: What a timed model's tasks run on without --platform, in words.
DEDICATED = "a core per task, codels taking their WCET (no --platform)"


def dedicated(description: ir.Description) -> Platform:
    """Today's timed model as a platform: a core for every task, codels taking exactly their WCET."""
    cores = sum(len(c.tasks) for c in description.components) or 1
    return Platform(cores=min(cores, MAX_CORES), policy="edf", best="wcet", path="")


def codel_owners(component: ir.Component) -> dict[str, list[ir.Codel]]:
    """Each task and service of a component with the codels its automaton runs."""
    out: dict[str, list[ir.Codel]] = {t.name: list(t.codels) for t in component.tasks}
    for s in component.services:
        out.setdefault(s.name, []).extend(s.fsm_codels())
    return out


class _Reader(rules._Reader):
    """The rule file's reader (positions, messages), reading a platform."""

    def scalar(self, node: yaml.Node, what: str, where: str = "") -> str | None:
        if not isinstance(node, yaml.ScalarNode) or node.value == "":
            self.error(node, f"{where}{what} must be a single value")
            return None
        return node.value

    def choice(self, node: yaml.Node, what: str, choices: tuple[str, ...]) -> str | None:
        """One of ``choices``; an error naming them (and the nearest) otherwise."""
        text = self.scalar(node, what)
        if text is not None and text not in choices:
            self.error(node, f"{what} is '{text}'; expected {' or '.join(choices)}", _suggest(text, list(choices)))
            return None
        return text

    def duration(self, node: yaml.Node, what: str) -> int | None:
        text = self.scalar(node, what)
        if text is None:
            return None
        value = parse_duration(text)
        if value is None or not math.isfinite(value):
            self.error(node, f"{what} is '{text}'; expected a duration", "write e.g. 10 ms, 1.5 ms or 500 us")
            return None
        return value

    def interval(self, node: yaml.Node, what: str) -> Interval | None:
        """``[best, worst]`` or one duration (both ends)."""
        if isinstance(node, yaml.ScalarNode):
            value = self.duration(node, what)
            return None if value is None else Interval(value, value)
        if not isinstance(node, yaml.SequenceNode) or len(node.value) != 2:
            self.error(node, f"{what} must be [best, worst] or one duration", "write e.g. [2 ms, 5 ms]")
            return None
        best, worst = (self.duration(n, what) for n in node.value)
        if best is None or worst is None:
            return None
        if best > worst:
            self.error(node, f"{what}: the best case {best / 1000:g} ms is longer than the worst {worst / 1000:g} ms")
            return None
        return Interval(best, worst)

    def mapping(self, node: yaml.Node, what: str) -> list[tuple[yaml.Node, yaml.Node]] | None:
        if not isinstance(node, yaml.MappingNode):
            self.error(node, f"{what} must be a mapping")
            return None
        seen: set[str] = set()
        out = []
        for k, v in node.value:
            if k.value in seen:
                self.error(k, f"{what}: key '{k.value}' given twice")
                continue
            seen.add(k.value)
            out.append((k, v))
        return out

    def component(self, node: yaml.Node, name: str) -> ir.Component | None:
        found = next((c for c in self.description.components if c.name == name), None)
        if found is None:
            names = [c.name for c in self.description.components]
            self.error(node, f"unknown component '{name}'", _suggest(name, names))
        return found

    def codel(self, node: yaml.Node) -> tuple[str, str, str] | None:
        """``Component.Owner.codel``: a codel of the automaton of a task or service."""
        parts = str(node.value).split(".")
        if len(parts) != 3 or not all(parts):
            self.error(node, f"'{node.value}' is not Component.Owner.codel",
                       "name a codel by its component, the task or service that runs it, and its name")
            return None
        component = self.component(node, parts[0])
        if component is None:
            return None
        owners = codel_owners(component)
        if parts[1] not in owners:
            self.error(node, f"component {parts[0]} has no task or service '{parts[1]}'",
                       _suggest(parts[1], list(owners)))
            return None
        names = list(dict.fromkeys(c.name for c in owners[parts[1]]))
        if parts[2] not in names:
            self.error(node, f"{parts[0]}.{parts[1]} runs no codel '{parts[2]}'",
                       _suggest(parts[2], names) if names else f"{parts[0]}.{parts[1]} runs no codel")
            return None
        return (parts[0], parts[1], parts[2])

    def task(self, node: yaml.Node) -> tuple[str, str] | None:
        parts = str(node.value).split(".")
        if len(parts) != 2 or not all(parts):
            self.error(node, f"'{node.value}' is not Component.task")
            return None
        component = self.component(node, parts[0])
        if component is None:
            return None
        names = [t.name for t in component.tasks]
        if parts[1] not in names:
            self.error(node, f"component {parts[0]} has no task '{parts[1]}'", _suggest(parts[1], names))
            return None
        return (parts[0], parts[1])

    def platform(self, root: yaml.Node | None) -> Platform | None:
        if not isinstance(root, yaml.MappingNode):
            self.reporter.error(self.span(root) if root is not None else Span(self.path, 1, 1),
                                "a platform file is a mapping with at least 'cores'", "write e.g. 'cores: 2'")
            return None
        fields: dict[str, yaml.Node] = {}
        for k, v in self.mapping(root, "the platform") or []:
            if k.value not in KEYS:
                self.error(k, f"unknown key '{k.value}'",
                           _suggest(k.value, list(KEYS)) or f"keys are {', '.join(KEYS)}")
            else:
                fields[k.value] = v
        if "cores" not in fields:
            self.error(root, "the platform has no 'cores'", "write e.g. 'cores: 2'")
            return None
        out = Platform(cores=0, path=self.path)
        text = self.scalar(fields["cores"], "cores")
        if text is not None:
            if not (text.isascii() and text.isdigit()) or not 1 <= int(text) <= MAX_CORES:
                self.error(fields["cores"], f"cores is '{text}'; expected a whole number from 1 to {MAX_CORES}")
            else:
                out.cores = int(text)
        for key, choices in (("policy", POLICIES), ("releases", RELEASES)):
            value = self.choice(fields[key], key, choices) if key in fields else None
            if value is not None:
                setattr(out, key, value)
        if "best" in fields:
            node = fields["best"]
            if isinstance(node, yaml.ScalarNode) and node.value == "wcet":
                out.best = "wcet"
            else:
                value = self.duration(node, "best")
                if value is not None:
                    out.best = value
        execution = self.mapping(fields["execution"], "execution") if "execution" in fields else []
        for k, v in execution or []:
            key = self.codel(k)
            span = self.interval(v, f"execution of {k.value}")
            if key is not None and span is not None and self.sensible(v, f"execution of {k.value}", span,
                                                                      self.owner_task(key)):
                out.execution[key] = span
        distributions = self.mapping(fields["distributions"], "distributions") if "distributions" in fields else []
        for k, v in distributions or []:
            key = self.codel(k)
            law = self.distribution(v, f"distribution of {k.value}")
            if key is not None and law is not None:
                out.distributions[key] = law
        tasks = self.mapping(fields["tasks"], "tasks") if "tasks" in fields else []
        for k, v in tasks or []:
            key = self.task(k)
            settings = self.task_settings(v, str(k.value), self.ir_task(key), out.policy)
            if key is not None and settings is not None:
                out.tasks[key] = settings
        return out

    def distribution(self, node: yaml.Node, what: str) -> Distribution | None:
        """``uniform``, ``{triangular: MODE}`` or ``{normal: [MEAN, SD]}`` (durations)."""
        hint = "write uniform, {triangular: 6 ms} (its mode) or {normal: [5 ms, 1 ms]} (mean, sd)"
        if isinstance(node, yaml.ScalarNode):
            if node.value != "uniform":
                self.error(node, f"{what} is '{node.value}'; expected one of {', '.join(DISTRIBUTIONS)}",
                           _suggest(node.value, list(DISTRIBUTIONS)) or hint)
                return None
            return Distribution()
        items = self.mapping(node, what)
        if items is None:
            return None
        if len(items) != 1:
            self.error(node, f"{what} must name one distribution", hint)
            return None
        k, v = items[0]
        if k.value == "triangular":
            mode = self.duration(v, f"{what}: the mode")
            return None if mode is None else Distribution("triangular", mode_us=mode)
        if k.value == "normal":
            if not isinstance(v, yaml.SequenceNode) or len(v.value) != 2:
                self.error(v, f"{what}: normal takes [mean, sd]", hint)
                return None
            mean, sd = (self.duration(n, f"{what}: normal") for n in v.value)
            if mean is None or sd is None:
                return None
            if sd <= 0:
                self.error(v.value[1], f"{what}: the standard deviation must be positive")
                return None
            return Distribution("normal", mean_us=mean, sd_us=sd)
        self.error(k, f"{what}: unknown distribution '{k.value}'", _suggest(str(k.value), list(DISTRIBUTIONS)) or hint)
        return None

    def ir_task(self, key: tuple[str, str] | None) -> ir.Task | None:
        """The description's task named by ``key`` (None when the key was wrong)."""
        if key is None:
            return None
        component = next(c for c in self.description.components if c.name == key[0])
        return next(t for t in component.tasks if t.name == key[1])

    def task_settings(self, node: yaml.Node, name: str, task: ir.Task | None, policy: str) -> TaskSettings | None:
        items = self.mapping(node, f"task {name}")
        if items is None:
            return None
        out = TaskSettings()
        for k, v in items:
            if k.value == "delay":
                out.delay = self.interval(v, f"delay of {name}")
                if out.delay is not None and not self.sensible(v, f"delay of {name}", out.delay, task):
                    out.delay = None
            elif k.value == "suspend" and isinstance(v, yaml.MappingNode):
                items = dict((key.value, (key, value)) for key, value in self.mapping(v, f"suspend of {name}") or [])
                for key, _ in items.values():
                    if key.value not in SUSPEND_KEYS:
                        self.error(key, f"suspend of {name}: unknown key '{key.value}'",
                                   _suggest(key.value, list(SUSPEND_KEYS)) or "keys are for, after")
                if "after" in items:
                    out.suspend_after = self.choice(items["after"][1], f"suspend of {name}: after",
                                                    SUSPEND_AFTER) or "release"
                    if out.suspend_after == "grant" and policy != "edf":
                        self.error(items["after"][1], f"suspend of {name}: after grant needs policy edf",
                                   "under fixed priority a task is granted a core for each codel")
                if "for" not in items:
                    self.error(v, f"suspend of {name} has no 'for'", "write e.g. {for: 11 ms, after: grant}")
                else:
                    out.suspend = self.suspension(items["for"][1], name, task)
            elif k.value == "suspend":
                out.suspend = self.suspension(v, name, task)
            elif k.value == "priority":
                text = self.scalar(v, f"priority of {name}")
                if text is not None and (not (text.isascii() and text.isdigit()) or int(text) > LOWEST_PRIORITY):
                    self.error(v, f"priority of {name} is '{text}'; expected 0 (highest) to {LOWEST_PRIORITY}")
                elif text is not None:
                    out.priority = int(text)
            else:
                self.error(k, f"task {name}: unknown key '{k.value}'", _suggest(k.value, list(TASK_KEYS)))
        return out


    def owner_task(self, key: tuple[str, str, str]) -> ir.Task | None:
        """The task that runs codel ``key``'s owner: the task itself, or a service's (None: the control task)."""
        component = next(c for c in self.description.components if c.name == key[0])
        tasks = {t.name: t for t in component.tasks}
        if key[1] in tasks:
            return tasks[key[1]]
        service = next((s for s in component.services if s.name == key[1]), None)
        return tasks.get(service.task) if service is not None and service.task else None

    def sensible(self, node: yaml.Node, what: str, span: Interval, task: ir.Task | None) -> bool:
        """A duration within :data:`MAX_PERIODS` periods of ``task`` (else of the longest period): an error past
        them, a warning past one period; False when refused."""
        periods = [round(t.period.seconds * 1e6) for c in self.description.components for t in c.tasks if t.period]
        own = task is not None and task.period is not None
        period = round(task.period.seconds * 1e6) if own else max(periods, default=0)
        if not period or span.worst_us <= period:
            return True
        whose = f"the period of {task.name}" if own else "the longest period"
        if span.worst_us > MAX_PERIODS * period:
            self.error(node, f"{what}: {span.worst_us / 1000:g} ms is more than {MAX_PERIODS} times {whose} "
                             f"({period / 1000:g} ms)", "a duration in ms of the order of the periods is expected")
            return False
        self.reporter.warning(self.span(node), f"{what}: {span.worst_us / 1000:g} ms is longer than {whose} "
                                               f"({period / 1000:g} ms)")
        return True

    def suspension(self, node: yaml.Node, name: str, task: ir.Task | None) -> Interval | None:
        """``suspend``: a duration or interval shorter than the task's period (a periodic task's only)."""
        span = self.interval(node, f"suspend of {name}")
        if span is None or task is None:
            return None
        if task.period is None:
            self.error(node, f"suspend of {name}: task {name} has no period",
                       "a task suspends after each release of its period; a task without period has none")
            return None
        period = round(task.period.seconds * 1e6)
        if span.worst_us >= period:
            self.error(node, f"suspend of {name}: {span.worst_us / 1000:g} ms is not shorter than its period, "
                             f"{period / 1000:g} ms", "a task that suspends for a whole period never runs in time")
            return None
        return span


def load_platform(path: Path, description: ir.Description, reporter: Reporter) -> Platform | None:
    """Read and check a platform file against the description; problems go to ``reporter`` (None then)."""
    ok, root = compose_file(path, reporter, "platform file")
    if not ok:
        return None
    out = _Reader(str(path), description, reporter).platform(root)
    return None if reporter.has_errors else out
