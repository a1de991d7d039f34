"""Reading a campaign file (YAML): its models, its checks and the values they vary over; every problem is named
with file:line:column, as in a rule file, before anything runs.

```yaml
campaign: dala                      # a name (default: the file's)
models:
  ndd: {paths: [NDD.gen]}           # files or directories, relative to this file
  dala-timed:
    paths: [.]                      # rules.yaml of a directory is read, as verify reads it
    timed: true                     # or {tick: 1 ms, default-wcet: 25 ms, observers: observers.yaml}
  sensing:
    paths: [RFLEX.gen, POM.gen]
    timed: {platform: platforms/one-core.yaml, client: missions/sensing.yaml}
  corpus: {each: "${corpus}"}       # one model per .gen file of a directory (--set corpus=DIR)
options: {max-states: 2000000}      # every check's search options (verify's, without dashes in front)
vary: {wcet-scale: [1, 2]}          # every check's axes: the cross product of their values
checks:
  - check: property                 # deadlock, property, observer, response-times (genom2bip/campaign/kinds.py)
    model: ndd
    files: [properties/NDD.mcl]     # one job per property (only: [names] for some)
    method: explore                 # or compositional: invariants, localization
  - check: observer
    model: dala-timed
    method: compositional
    vary: {default-wcet: [0 ms, 25 ms]}   # this check's axes, over the file's
  - check: response-times           # one job per point: every task's response time (of: [tasks, services])
    model: sensing
    vary: {cores: [1, 2, 3, 4], policy: [edf, fixed-priority]}   # over the platform file's
  - check: smc                      # statistical model checking (docs/smc.md): one job per point
    model: sensing
    smc: {time-bound: 1 s, epsilon: 0.01, delta: 0.05, seed: 1}   # or threshold, runs, proba
    vary: {cores: [1, 2]}
```
"""
from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import yaml

from genom2bip.campaign.axes import AxisKind, axis_kind
from genom2bip.campaign.kinds import KINDS, METHODS, RESPONSE_OWNERS
from genom2bip.campaign.params import ModelParams
from genom2bip.filenames import name_problem
from genom2bip.yamlfile import span_of
from runtime.diagnostics import Reporter, Span

TOP = ("campaign", "doc", "models", "options", "timeout", "vary", "checks")
MODEL_KEYS = ("paths", "each", "rules", "no-rules", "defines", "include", "root", "timed", "doc")
TIME_KEYS = ("tick", "default-wcet", "observers", "platform", "client")
CHECK_KEYS = ("check", "model", "method", "options", "timeout", "vary", "doc")
OBSERVER_KINDS = ("overrun", "latency")
#: Keys of a statistical model checking check's ``smc`` mapping.
SMC_KEYS = ("time-bound", "epsilon", "delta", "threshold", "runs", "seed", "proba")
#: Search options: key -> (SearchOptions field, reader).  Integers are 0 or more.
OPTION_FIELDS = {
    "engine": "engine", "max-states": "max_states", "max-depth": "max_depth", "max-memory": "max_memory_mb",
    "dfs": "dfs", "requests": "requests", "no-reduce": "reduce", "externs": "externs", "por": "por",
    "workers": "workers", "store": "store", "bits": "bits", "solver": "solver", "check-states": "check_states",
}
INT_OPTIONS = ("max-states", "max-depth", "max-memory", "requests", "workers", "bits", "check-states")
BOOL_OPTIONS = ("dfs", "no-reduce", "por")
CHOICES = {"engine": ("compiled", "python", "spin"), "store": ("exact", "compact", "bitstate")}
VARIABLE = re.compile(r"\$\{([A-Za-z_]\w*)\}")


@dataclass
class ModelSpec:
    """A model of the file: its parameters (``each``: one model per file of a directory), where it is written."""

    name: str
    params: ModelParams
    span: Span


@dataclass
class Axis:
    """``key: [values]``: the values as written (JSON types) and where each is."""

    key: str
    kind: AxisKind
    name: str  # the macro or task of a named axis
    values: list[Any]
    parsed: list[Any]
    span: Span


@dataclass
class CheckSpec:
    """A check of the file: its kind, its model(s), method, own keys, search options and axes."""

    kind: str
    model: str
    method: str
    span: Span
    files: list[str] = field(default_factory=list)
    only: list[str] | None = None
    kinds: tuple[str, ...] = OBSERVER_KINDS
    of: tuple[str, ...] = RESPONSE_OWNERS  # response times: whose are recorded
    options: dict[str, Any] = field(default_factory=dict)  # SearchOptions keyword arguments
    axes: list[Axis] = field(default_factory=list)
    timeout: float | None = None  # seconds of wall clock a job may take before it is stopped
    spans: dict[str, Span] = field(default_factory=dict)  # key -> where its value is
    smc: tuple[tuple[str, Any], ...] = ()  # statistical model checking: SmcSettings fields, as read


@dataclass
class Campaign:
    name: str
    path: Path
    doc: str
    models: dict[str, list[ModelSpec]]  # the file's name -> its models (several with ``each``)
    checks: list[CheckSpec]

    @property
    def base(self) -> Path:
        return self.path.resolve().parent


def _plain(node: yaml.Node) -> Any:
    return yaml.safe_load(yaml.serialize(node))


class _Reader:
    """Walks the node tree so that every value keeps its position for messages."""

    def __init__(self, path: Path, reporter: Reporter, settings: Mapping[str, str]) -> None:
        self.path, self.reporter, self.settings = path, reporter, settings
        self.base = path.resolve().parent
        self.timeout: float | None = None  # the file's, for every check that gives none

    def span(self, node: yaml.Node) -> Span:
        return span_of(self.path, node)

    def error(self, node: yaml.Node, message: str, hint: str | None = None) -> None:
        self.reporter.error(self.span(node), message, hint)

    def mapping(self, node: yaml.Node, what: str, keys: tuple[str, ...]) -> dict[str, tuple[yaml.Node, yaml.Node]]:
        """The keys of a mapping, each unknown or repeated key reported; {} (reported) for another node."""
        if not isinstance(node, yaml.MappingNode):
            self.error(node, f"{what}: a mapping expected (keys: {', '.join(keys)})")
            return {}
        out: dict[str, tuple[yaml.Node, yaml.Node]] = {}
        for k, v in node.value:
            name = k.value if isinstance(k, yaml.ScalarNode) else None
            if name not in keys:
                self.error(k, f"{what}: unknown key {_plain(k)!r} (keys: {', '.join(keys)})")
            elif name in out:
                self.error(k, f"{what}: {name!r} given twice")
            else:
                out[name] = (k, v)
        return out

    def text(self, node: yaml.Node, what: str) -> str | None:
        if not isinstance(node, yaml.ScalarNode) or node.value == "":
            self.error(node, f"{what}: a single value expected")
            return None
        return node.value

    def strings(self, node: yaml.Node, what: str) -> list[str] | None:
        """A value or a list of values (as text)."""
        items = node.value if isinstance(node, yaml.SequenceNode) else [node]
        out = [self.text(n, what) for n in items]
        return None if any(v is None for v in out) else out

    def file_path(self, node: yaml.Node, what: str, must_exist: bool = True) -> str | None:
        """A path relative to the campaign file, ``${NAME}`` replaced by --set NAME=VALUE or the environment (a path
        that starts with one is relative to the working directory, as the command line's paths are)."""
        text = self.text(node, what)
        if text is None:
            return None
        unset = [m.group(1) for m in VARIABLE.finditer(text)
                 if m.group(1) not in self.settings and m.group(1) not in os.environ]
        if unset:
            self.error(node, f"{what}: ${{{unset[0]}}} is not set", f"give --set {unset[0]}=VALUE")
            return None
        given = text.startswith("${")  # a path that starts with a setting is the command line's: from its cwd
        text = VARIABLE.sub(lambda m: self.settings.get(m.group(1), os.environ.get(m.group(1), "")), text)
        path = (Path.cwd() if given else self.base) / Path(text).expanduser()
        path = path.resolve()
        if must_exist and not path.exists():
            self.error(node, f"{what}: {text}: no such file or directory")
            return None
        return str(path)

    # -- models ----------------------------------------------------------------------------------------------
    def models(self, node: yaml.Node) -> dict[str, list[ModelSpec]]:
        if not isinstance(node, yaml.MappingNode) or not node.value:
            self.error(node, "models: a mapping of names to models expected (e.g. ndd: {paths: [NDD.gen]})")
            return {}
        out: dict[str, list[ModelSpec]] = {}
        for k, v in node.value:
            name = self.text(k, "a model's name")
            if name is None:
                continue
            if name in out:
                self.error(k, f"model {name!r} given twice")
                continue
            out[name] = self.model(name, v)
        return out

    def model(self, name: str, node: yaml.Node) -> list[ModelSpec]:
        """A model's parameters; with ``each``, one model per .gen file of the directory (named by its file)."""
        fields = self.mapping(node, f"model {name}", MODEL_KEYS)
        if not fields:
            return []
        if ("paths" in fields) == ("each" in fields):
            self.error(node, f"model {name}: exactly one of 'paths' (files or directories) and 'each' "
                             "(a directory: one model per .gen file) expected")
            return []
        kw: dict[str, Any] = {}
        if "rules" in fields:
            kw["rules"] = self.file_path(fields["rules"][1], f"model {name}: rules")
        if "no-rules" in fields:
            kw["no_rules"] = self.boolean(fields["no-rules"][1], f"model {name}: no-rules")
        if "defines" in fields:
            kw["defines"] = self.defines(fields["defines"][1], name)
        if "include" in fields:
            dirs = [self.file_path(n, f"model {name}: include") for n in _items(fields["include"][1])]
            kw["include_dirs"] = tuple(d for d in dirs if d is not None)
        if "root" in fields:
            kw["root"] = self.text(fields["root"][1], f"model {name}: root")
        if "timed" in fields:
            kw.update(self.timed(fields["timed"][1], name))
        if "paths" in fields:
            paths = [self.file_path(n, f"model {name}: paths") for n in _items(fields["paths"][1])]
            if any(p is None for p in paths) or not paths:
                return []
            return [ModelSpec(name, ModelParams(tuple(paths), **kw), self.span(node))]
        where = self.file_path(fields["each"][1], f"model {name}: each")
        if where is None:
            return []
        files = sorted(Path(where).glob("*.gen")) if Path(where).is_dir() else []
        if not files:
            self.error(fields["each"][1], f"model {name}: each: no .gen file in {where}")
        return [ModelSpec(f.stem, ModelParams((str(f),), **kw), self.span(node)) for f in files]

    def boolean(self, node: yaml.Node, what: str) -> bool:
        value = _plain(node)
        if not isinstance(value, bool):
            self.error(node, f"{what}: true or false expected")
            return False
        return value

    def defines(self, node: yaml.Node, name: str) -> tuple[tuple[str, str], ...]:
        value = _plain(node)
        if not isinstance(value, dict) or not all(isinstance(k, str) and k.isidentifier() for k in value):
            self.error(node, f"model {name}: defines: a mapping of macro names to values expected")
            return ()
        return tuple(sorted((k, "1" if v is None else str(int(v) if isinstance(v, bool) else v))
                            for k, v in value.items()))

    def timed(self, node: yaml.Node, name: str) -> dict[str, Any]:
        """``timed: true`` or a mapping of tick, default-wcet, observers, platform and client."""
        from genom2bip.observers import parse_duration

        if isinstance(node, yaml.ScalarNode):
            return {"timed": self.boolean(node, f"model {name}: timed")}
        fields = self.mapping(node, f"model {name}: timed", TIME_KEYS)
        out: dict[str, Any] = {"timed": True}
        for key, field_name in (("tick", "tick_us"), ("default-wcet", "default_wcet_us")):
            if key in fields:
                v = fields[key][1]
                us = parse_duration(v.value) if isinstance(v, yaml.ScalarNode) else None
                if us is None or (key == "tick" and us <= 0):
                    self.error(v, f"model {name}: {key}: a duration expected (e.g. 1 ms, 500 us)")
                out[field_name] = us
        for key in ("observers", "platform", "client"):
            if key in fields:
                out[key] = self.file_path(fields[key][1], f"model {name}: {key}")
        return out

    def seconds(self, node: yaml.Node, what: str) -> float | None:
        """A positive duration (``10 min``, ``30 s``) in seconds."""
        from genom2bip.observers import parse_duration

        us = parse_duration(node.value) if isinstance(node, yaml.ScalarNode) else None
        if not us:
            self.error(node, f"{what}: a positive duration expected (e.g. 30 s, 10 min)")
            return None
        return us / 1e6

    # -- options and axes ------------------------------------------------------------------------------------
    def options(self, node: yaml.Node, what: str) -> dict[str, Any]:
        """Search options as :class:`~genom2bip.verify.SearchOptions` keyword arguments."""
        fields = self.mapping(node, f"{what}options", tuple(OPTION_FIELDS))
        out: dict[str, Any] = {}
        for key, (_, v) in fields.items():
            value = _plain(v)
            if key in INT_OPTIONS:
                if isinstance(value, bool) or not isinstance(value, int) or value < 0:
                    self.error(v, f"{what}options: {key}: an integer (0 or more) expected")
                    continue
            elif key in BOOL_OPTIONS:
                if not isinstance(value, bool):
                    self.error(v, f"{what}options: {key}: true or false expected")
                    continue
                value = not value if key == "no-reduce" else value
            elif key in CHOICES:
                if value not in CHOICES[key]:
                    self.error(v, f"{what}options: {key}: one of {', '.join(CHOICES[key])} expected")
                    continue
            elif key == "externs":
                value = self.file_path(v, f"{what}options: externs")
                if value is None:
                    continue
            elif not isinstance(value, str):
                self.error(v, f"{what}options: {key}: a single value expected")
                continue
            out[OPTION_FIELDS[key]] = value
        return out

    def axes(self, node: yaml.Node, what: str) -> list[Axis]:
        """``vary:``: each axis's kind, and each value read by it (a value it cannot read is located)."""
        if not isinstance(node, yaml.MappingNode):
            self.error(node, f"{what}vary: a mapping of axes to lists of values expected (e.g. wcet-scale: [1, 2])")
            return []
        out: list[Axis] = []
        for k, v in node.value:
            key = self.text(k, f"{what}vary: an axis")
            if key is None:
                continue
            try:
                kind, name = axis_kind(key)
            except ValueError as exc:
                self.error(k, f"{what}vary: {exc}")
                continue
            if any(a.key == key for a in out):
                self.error(k, f"{what}vary: {key!r} given twice")
                continue
            if not isinstance(v, yaml.SequenceNode) or not v.value:
                self.error(v, f"{what}vary: {key}: a list of values expected")
                continue
            values, parsed, ok = [], [], True
            for item in v.value:
                value = _plain(item)
                try:
                    parsed.append(kind.read(value))
                except ValueError as exc:
                    self.error(item, f"{what}vary: {key}: {exc}, got {value!r}")
                    ok = False
                else:
                    if kind.path:
                        parsed[-1] = self.file_path(item, f"{what}vary: {key}")
                        ok = ok and parsed[-1] is not None
                values.append(value)
            if any(p == q for i, p in enumerate(parsed) for q in parsed[:i]):
                self.error(v, f"{what}vary: {key}: a value is given twice")
                ok = False
            if ok:
                out.append(Axis(key, kind, name, values, parsed, self.span(k)))
        return out

    # -- checks ----------------------------------------------------------------------------------------------
    def checks(self, node: yaml.Node, models: dict[str, list[ModelSpec]], options: dict, axes: list[Axis]):
        if not isinstance(node, yaml.SequenceNode) or not node.value:
            self.error(node, "checks: a list of checks expected (each with check: and model:)")
            return []
        out = []
        for n, item in enumerate(node.value, 1):
            check = self.check(item, n, models, options, axes)
            if check is not None:
                out.append(check)
        return out

    def check(self, node, n: int, models, options: dict, axes: list[Axis]) -> CheckSpec | None:
        """Check ``n``: its kind and the keys of that kind, its model, method, options, timeout and axes."""
        what = f"check {n}"
        keys = CHECK_KEYS + tuple(k for kind in KINDS.values() for k in kind.keys if k not in CHECK_KEYS)
        fields = self.mapping(node, what, tuple(dict.fromkeys(keys)))
        if not fields:
            return None
        if "check" not in fields or "model" not in fields:
            self.error(node, f"{what}: 'check' (one of {', '.join(KINDS)}) and 'model' expected")
            return None
        kind_name = self.text(fields["check"][1], f"{what}: check")
        kind = KINDS.get(kind_name or "")
        if kind is None:
            if kind_name is not None:
                self.error(fields["check"][1], f"{what}: unknown check {kind_name!r} (checks: {', '.join(KINDS)})")
            return None
        what = f"check {n} ({kind.name})"
        for key, (k, _) in fields.items():
            if key not in CHECK_KEYS and key not in kind.keys:
                self.error(k, f"{what}: {key!r} belongs to another kind of check (this one takes: "
                              f"{', '.join(CHECK_KEYS + kind.keys)})")
        for key in kind.required:
            if key not in fields:
                self.error(node, f"{what}: {key!r} expected")
        model = self.text(fields["model"][1], f"{what}: model")
        if model is not None and model not in models:
            self.error(fields["model"][1], f"{what}: no model {model!r} (models: {', '.join(models)})")
        method = "explore"
        if "method" in fields:
            method = self.text(fields["method"][1], f"{what}: method") or method
            if method not in METHODS:
                self.error(fields["method"][1], f"{what}: method: one of {', '.join(METHODS)} expected")
        spec = CheckSpec(kind.name, model or "", method, self.span(node),
                         spans={k: self.span(v) for k, (_, v) in fields.items()})
        if "files" in fields:
            spec.files = [p for p in (self.file_path(n, f"{what}: files") for n in _items(fields["files"][1])) if p]
        if "only" in fields:
            spec.only = self.strings(fields["only"][1], f"{what}: only") or []
        if "kinds" in fields:
            kinds = self.strings(fields["kinds"][1], f"{what}: kinds") or []
            for bad in (k for k in kinds if k not in OBSERVER_KINDS):
                self.error(fields["kinds"][1], f"{what}: kinds: {bad!r} is not one of {', '.join(OBSERVER_KINDS)}")
            spec.kinds = tuple(kinds)
        if "of" in fields:
            of = self.strings(fields["of"][1], f"{what}: of") or []
            for bad in (k for k in of if k not in RESPONSE_OWNERS):
                self.error(fields["of"][1], f"{what}: of: {bad!r} is not one of {', '.join(RESPONSE_OWNERS)}")
            spec.of = tuple(of)
        if "smc" in fields:
            spec.smc = self.smc(fields["smc"][1], f"{what}: smc")
        spec.options = {**options, **(self.options(fields["options"][1], f"{what}: ") if "options" in fields else {})}
        spec.timeout = self.seconds(fields["timeout"][1], f"{what}: timeout") if "timeout" in fields else self.timeout
        own = self.axes(fields["vary"][1], f"{what}: ") if "vary" in fields else []
        spec.axes = [a for a in axes if all(a.key != b.key for b in own)] + own
        if model in models:
            self._fits(spec, kind, models[model], fields["model"][1], what)
        return spec

    def smc(self, node: yaml.Node, what: str) -> tuple[tuple[str, Any], ...]:
        """``{time-bound: 1 s, epsilon: 0.01, delta: 0.05, threshold: P, runs: N, seed: S, proba: FILE}``."""
        from genom2bip.durations import parse_duration
        from genom2bip.loading import UsageError
        from genom2bip.verify.smc import SmcSettings

        fields = self.mapping(node, what, SMC_KEYS)
        out: dict[str, Any] = {}
        for key, (_, v) in fields.items():
            text = self.text(v, f"{what}: {key}")
            if text is None:
                continue
            if key == "time-bound":
                value = parse_duration(text)
                if value is None:
                    self.error(v, f"{what}: time-bound: {text!r} is not a duration (e.g. 1 s)")
                    continue
                out["horizon_us"] = int(value)
            elif key == "proba":
                path = self.file_path(v, f"{what}: proba")
                if path:
                    out["proba"] = path
            else:
                kind = int if key in ("runs", "seed") else float
                try:
                    out[key] = kind(text)
                except ValueError:
                    self.error(v, f"{what}: {key}: {text!r} is not {'a whole number' if kind is int else 'a number'}")
                    continue
            try:
                SmcSettings(**{"horizon_us": 1, **out}).check()
            except UsageError as exc:
                self.error(v, f"{what}: {exc.messages[0].replace('--', '')}")
                out.pop(key, None)
        return tuple(sorted(out.items()))

    def _fits(self, spec: CheckSpec, kind, models: list[ModelSpec], node, what: str) -> None:
        """A timed check or a timed axis on a model without time is refused where the check names it; a policy
        without a platform (no file, no cores) where the axis is."""
        cores = any(a.kind.name in ("cores", "platform") for a in spec.axes)
        for axis in spec.axes:
            if axis.kind.name == "policy" and not cores and any(m.params.platform is None for m in models):
                self.reporter.error(axis.span, f"{what}: axis policy needs a platform, and model {spec.model} has "
                                               "none", "give the model timed: {platform: FILE}, or vary cores too")
        untimed = [m.name for m in models if not m.params.timed]
        if not untimed:
            return
        if kind.timed:
            self.error(node, f"{what}: model {spec.model} is not timed", "add timed: true to the model")
        for axis in spec.axes:
            if axis.kind.timed:
                self.reporter.error(axis.span, f"{what}: axis {axis.key} changes only a timed model, and model "
                                               f"{spec.model} is not timed", "add timed: true to the model")

    def campaign(self, root: yaml.Node | None) -> Campaign | None:
        """The whole file: its name, models, defaults (options, timeout, axes) and checks."""
        if not isinstance(root, yaml.MappingNode):
            self.reporter.error(Span(str(self.path), 1, 1), "a campaign file is a mapping with 'models' and "
                                                            "'checks' (and 'campaign', 'options', 'vary')")
            return None
        fields = self.mapping(root, "campaign file", TOP)
        for key in ("models", "checks"):
            if key not in fields:
                self.error(root, f"campaign file: {key!r} expected")
        if "models" not in fields or "checks" not in fields:
            return None
        name = self.text(fields["campaign"][1], "campaign") if "campaign" in fields else self.path.stem
        problem = name_problem(name) if name is not None else None
        if problem:  # the name is a directory under out/: one plain component of a path
            where = fields["campaign"][1] if "campaign" in fields else None
            self.reporter.error(self.span(where) if where is not None else Span(str(self.path), 0, 0),
                                f"campaign: {name!r} cannot name its output directory: {problem}")
            return None
        doc = str(_plain(fields["doc"][1])) if "doc" in fields else ""
        models = self.models(fields["models"][1])
        options = self.options(fields["options"][1], "") if "options" in fields else {}
        if "timeout" in fields:
            self.timeout = self.seconds(fields["timeout"][1], "timeout")
        axes = self.axes(fields["vary"][1], "") if "vary" in fields else []
        checks = self.checks(fields["checks"][1], models, options, axes)
        return Campaign(name or self.path.stem, self.path, doc, models, checks)


def _items(node: yaml.Node) -> list[yaml.Node]:
    return node.value if isinstance(node, yaml.SequenceNode) else [node]


def read_campaign(path: str | Path, settings: Mapping[str, str] | None = None,
                  reporter: Reporter | None = None) -> Campaign:
    """The campaign in ``path``; raises DiagnosticError listing every problem (file:line:column).

    ``settings``: the values of ``${NAME}`` in paths (the command line's ``--set NAME=VALUE``).
    """
    from genom2bip.yamlfile import compose_file  # bounded: size, nesting, aliases, numbers

    path = Path(path)
    reporter = reporter or Reporter()
    ok, root = compose_file(path, reporter, "campaign file")
    campaign = _Reader(path, reporter, settings or {}).campaign(root) if ok else None
    reporter.raise_if_errors()
    return campaign
