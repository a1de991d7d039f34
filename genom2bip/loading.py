"""Descriptions, rule files and observer files read from plain parameters: what every verb and the verification
API load before they build a model.

Problems are diagnostics handed to ``report(diagnostics, sources)`` as each
file is read (warnings too), so a terminal shows them in the order they are
found; an error then stops the reading with :class:`InputError`.  Without
``report``, the diagnostics travel in the error (and warnings are kept by the
caller's :class:`Diagnostics`), so a caller without a terminal loses nothing.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Mapping, Sequence

from genom2bip.ir import Description
from runtime.diagnostics import Diagnostic, DiagnosticError, Reporter, SourceCache
from runtime.errors import Genom2bipError

DESCRIPTION_SUFFIXES = (".gen",)

#: ``report(diagnostics, sources)``: where a reader's diagnostics go as they are found.
Report = Callable[[Sequence[Diagnostic], "SourceCache | None"], None]


class InputError(Genom2bipError):
    """Bad input: ``messages`` say what (one line each); ``groups`` the diagnostics not handed to a ``report``."""

    def __init__(self, messages: Sequence[str] = (), groups: Sequence[DiagnosticError] = ()) -> None:
        self.messages, self.groups = list(messages), list(groups)
        super().__init__("\n".join([*self.messages, *(g.render() for g in self.groups)]))


class UsageError(InputError):
    """Settings that do not go together (the command line's usage errors)."""


class Diagnostics:
    """Where the diagnostics of one load go: to ``report`` as they come, else kept here (``kept``)."""

    def __init__(self, report: Report | None = None) -> None:
        self.report = report
        self.kept: list[DiagnosticError] = []

    def take(self, diagnostics: Sequence[Diagnostic], sources: SourceCache | None, failed: bool) -> None:
        """Pass diagnostics on (or keep them); raise :class:`InputError` when they hold an error."""
        if diagnostics:
            if self.report is not None:
                self.report(diagnostics, sources)
            else:
                self.kept.append(DiagnosticError(list(diagnostics), sources))
        if failed:
            raise InputError(groups=self.kept)

    def reporter(self, reporter: Reporter) -> None:
        self.take(reporter.diagnostics, reporter.sources, reporter.has_errors)


def description_files(paths: Sequence[str | Path]) -> list[Path]:
    """Expand directories into their description files (sorted); every path that is not one is named."""
    files: list[Path] = []
    missing: list[str] = []
    for raw in paths:
        path = Path(raw)
        if path.is_dir():
            found = sorted(p for p in path.iterdir() if p.suffix in DESCRIPTION_SUFFIXES and p.is_file())
            if not found:
                missing.append(f"{raw}: no {'/'.join(DESCRIPTION_SUFFIXES)} file in this directory")
            files.extend(found)
        elif path.exists() and not path.is_file():
            missing.append(f"{raw}: not a regular file (a device or a pipe cannot be read as a description)")
        elif path.exists():
            files.append(path)
        else:
            missing.append(f"{raw}: no such file or directory")
    if missing:
        raise InputError(missing)
    return files


def read_description(paths: Sequence[str | Path], defines: Mapping[str, str] | None = None,
                     include_dirs: Sequence[str] = (), check: bool = True,
                     diagnostics: Diagnostics | None = None) -> Description:
    """Parse (and check) the descriptions of ``paths`` (files or directories of ``.gen`` files)."""
    from genom2bip.checks import check_description
    from genom2bip.parser import parse_paths

    sink = diagnostics or Diagnostics()
    files = description_files(paths)
    reporter = Reporter()  # the parsers' warnings, then the checks' diagnostics
    try:
        description = parse_paths([str(f) for f in files], include_dirs=tuple(include_dirs),
                                  defines=dict(defines or {}), reporter=reporter)
    except DiagnosticError as exc:
        sink.take(exc.diagnostics, exc.sources, True)
        raise  # not reached: take raised
    if check:
        check_description(description, reporter)
    sink.take(reporter.diagnostics, reporter.sources, check and reporter.has_errors)
    return description


def rule_file(paths: Sequence[str | Path], rules: str | Path | None = None, no_rules: bool = False) -> Path | None:
    """``rules``; else, when descriptions are given as a directory, its ``rules.yaml``; None with ``no_rules``.

    A single description file does not pick up the rule file beside it: that
    file names the other modules of the system (verify one module alone).
    """
    if no_rules:
        return None
    if rules:
        return Path(rules)
    first = Path(paths[0])
    default = first / "rules.yaml"
    return default if first.is_dir() and default.is_file() else None


def read_rules(description: Description, paths: Sequence[str | Path], rules: str | Path | None = None,
               no_rules: bool = False, diagnostics: Diagnostics | None = None) -> list:
    """The description's constraints plus the rule file's (:func:`rule_file`), checked together."""
    from genom2bip.rules import all_rules

    path = rule_file(paths, rules, no_rules)
    if path is not None and rules and not path.is_file():
        raise InputError([f"{rules}: no such rule file"])
    reporter = Reporter()
    found = all_rules(description, path, reporter)
    (diagnostics or Diagnostics()).reporter(reporter)
    return found


@dataclass
class TimeSettings:
    """Symbolic time in plain parameters (``--timed``, or ``--monitor`` with ``ticks=False``)."""

    ticks: bool = True  # False: the observers alone, for a controller that measures real time
    tick_us: int | None = None  # None: the gcd of every period, WCET and observer bound
    default_wcet_us: int | None = None  # None: the builder's default (0, with a warning naming the codels)
    observers: str | Path | None = None  # latency observers (YAML); None: observers.yaml in the directory given
    platform: str | Path | None = None  # the computer (YAML, genom2bip/platform.py); None: a core per task
    cores: int | None = None  # over the platform file's; without a file, a platform of that many cores (EDF)
    policy: str | None = None  # over the platform file's (edf or fixed-priority); needs a file or ``cores``
    client: str | Path | None = None  # a mission whose steps are the environment; None: any request, once per period
    responses: bool = False  # response-time observers (a task's release to its end, a request to its report)
    exceptions: bool = True  # False: codels never throw (their declared yields only)


def observers_file(paths: Sequence[str | Path], observers: str | Path | None = None) -> Path | None:
    """``observers``; else ``observers.yaml`` in the directory of descriptions given."""
    if observers:
        return Path(observers)
    first = Path(paths[0])
    default = first / "observers.yaml"
    return default if first.is_dir() and default.is_file() else None


def time_options(description: Description, paths: Sequence[str | Path], settings: TimeSettings | None,
                 diagnostics: Diagnostics | None = None):
    """The builder's ``TimeOptions`` for ``settings`` (None: an untimed model), the observer file read and checked."""
    from genom2bip.build.timed import DEFAULT_WCET_US, TimeOptions
    from genom2bip.observers import load_observers

    if settings is None:
        return None
    latencies = []
    path = observers_file(paths, settings.observers)
    if path is not None:
        if not path.is_file():
            raise InputError([f"{path}: no such observer file"])
        reporter = Reporter()
        latencies = load_observers(path, description, reporter)
        (diagnostics or Diagnostics()).reporter(reporter)
    default = DEFAULT_WCET_US if settings.default_wcet_us is None else settings.default_wcet_us
    platform = _platform(description, settings, diagnostics)
    if settings.responses and platform is None:
        from genom2bip.platform import dedicated

        platform = dedicated(description)
    return TimeOptions(settings.tick_us, default, latencies, ticks=settings.ticks, platform=platform,
                       client=_client(description, settings.client, diagnostics), responses=settings.responses,
                       exceptions=settings.exceptions)


def _platform(description: Description, settings: TimeSettings, diagnostics: Diagnostics | None):
    """The platform file read and checked against the description, its cores and policy replaced by the settings';
    without a file, ``cores`` alone makes a platform of that many cores, the file's defaults for the rest (EDF);
    None with neither."""
    from dataclasses import replace

    from genom2bip.platform import MAX_CORES, POLICIES, Platform, load_platform

    path, cores, policy = settings.platform, settings.cores, settings.policy
    if cores is not None and not 1 <= cores <= MAX_CORES:
        raise UsageError([f"cores is {cores}; expected a whole number from 1 to {MAX_CORES}"])
    if policy is not None and policy not in POLICIES:
        raise UsageError([f"policy is {policy!r}; expected {' or '.join(POLICIES)}"])
    if path is None:
        if cores is None:
            if policy is not None:
                raise UsageError([f"policy {policy} needs a platform: a platform file or a number of cores"])
            return None
        return Platform(cores=cores, policy=policy or "edf", path=f"<{cores} cores>")
    if not Path(path).is_file():
        raise InputError([f"{path}: no such platform file"])
    reporter = Reporter()
    platform = load_platform(Path(path), description, reporter)
    (diagnostics or Diagnostics()).reporter(reporter)
    if platform is None:
        return None
    return replace(platform, cores=cores or platform.cores, policy=policy or platform.policy)


def _client(description: Description, path: str | Path | None, diagnostics: Diagnostics | None):
    """A mission file as the environment, every service it sends checked against the description."""
    from genom2bip.build.client import check
    from genom2bip.mission.spec import read_mission

    if path is None:
        return None
    if not Path(path).is_file():
        raise InputError([f"{path}: no such mission file"])
    reporter = Reporter()
    try:
        mission = read_mission(path, reporter)
    except DiagnosticError:
        mission = None
    if mission is not None:
        check(mission, description, reporter)
    (diagnostics or Diagnostics()).reporter(reporter)
    return mission
