"""The model a verification runs on, built from plain parameters: description files (rules, defines, include
paths, symbolic time) as ``genom2bip generate`` builds them, or one ``.bip`` file.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping, Sequence

from genom2bip.loading import Diagnostics, InputError, Report, TimeSettings, UsageError
from runtime.diagnostics import DiagnosticError

if TYPE_CHECKING:
    from genom2bip.variants import Variant


@dataclass
class Model:
    """A BIP model ready to verify: the package, its root instance, a title for reports, the warnings kept."""

    package: Any
    root: str
    title: str
    warnings: list[DiagnosticError] = field(default_factory=list)  # when no ``report`` was given
    description: Any = None  # the description IR it was built from (None for a .bip file)
    platform: Any = None  # the platform of a timed model (genom2bip.platform.Platform), None without

    @cached_property
    def flat(self):
        """The flattened system (``runtime.engine.EngineError`` for a model the engine cannot take)."""
        from runtime.engine import flatten
        return flatten(self.package, self.root)

    @property
    def timed(self) -> bool:
        return tick_us(self.package) is not None


def tick_us(package) -> int | None:
    """The resolution of a timed model (``@timed(tick_us=...)``), None for an untimed one."""
    ann = next((a for a in package.annotations if a.name == "timed"), None)
    return int(ann.arguments["tick_us"]) if ann else None


def untimed_codels(package) -> tuple[int, list[str]]:
    """``(default WCET in us, codels)``: the codels of a timed model that declare no WCET and take the default."""
    ann = next((a for a in package.annotations if a.name == "timed"), None)
    if ann is None or not ann.arguments.get("untimed"):
        return 0, []
    return int(ann.arguments["default_wcet_us"]), ann.arguments["untimed"].split(",")


def is_bip_file(paths: Sequence[str | Path]) -> bool:
    return len(paths) == 1 and str(paths[0]).endswith(".bip")


def open_bip(path: str | Path, root: str | None = None) -> Model:
    """A ``.bip`` file's model; ``root`` defaults to the last compound type (DiagnosticError for a bad file)."""
    from runtime.bip2 import parse_file

    if not Path(path).is_file():
        raise InputError([f"{path}: no such file"])
    package = parse_file(str(path))
    if not package.compound_types and not root:
        raise InputError([f"{path}: no compound type to use as root; give --root"])
    root = root or package.compound_types[-1].name + "()"
    return Model(package, root, f"{path} ({root})")


def build_model(paths: Sequence[str | Path], *, rules: str | Path | None = None, no_rules: bool = False,
                defines: Mapping[str, str] | None = None, include_dirs: Sequence[str] = (), name: str | None = None,
                root: str | None = None, time: TimeSettings | None = None, report: Report | None = None,
                variant: Variant | None = None) -> Model:
    """The model of description files or directories, built as ``genom2bip generate`` builds it; or of one ``.bip``.

    ``rules``: a rule file (default: ``rules.yaml`` in the directory given;
    ``no_rules`` keeps the descriptions' own constraints); ``defines`` and
    ``include_dirs`` go to the preprocessor; ``time`` adds symbolic time and
    the observers (default: untimed).  ``report(diagnostics, sources)``
    hears every file's diagnostics as they are found; without it the warnings
    are kept in the model and the errors carried by the exception.  Raises
    :class:`~genom2bip.loading.InputError` for bad input,
    ``DiagnosticError`` for a ``.bip`` file or a model that does not parse or
    build, :class:`~genom2bip.generate.GenerateError` for a model that cannot
    be generated.  ``variant`` (:class:`genom2bip.variants.Variant`) scales every WCET (the default one of
    ``time`` too) and replaces periods before the model is built: a sweep's point.
    """
    from genom2bip.generate import model_of, system_name
    from genom2bip.loading import read_description, read_rules, time_options

    if is_bip_file(paths):
        return open_bip(paths[0], root)
    if any(str(p).endswith(".bip") for p in paths):
        raise UsageError(["give either one .bip file or description files, not both"])
    diagnostics = Diagnostics(report)
    description = read_description(paths, defines, include_dirs, diagnostics=diagnostics)
    if variant is not None and not variant.identity:
        from genom2bip.variants import apply_variant, scaled

        description = apply_variant(description, variant)
        if time is not None and time.default_wcet_us:
            time = replace(time, default_wcet_us=scaled(time.default_wcet_us, variant.wcet_scale))
    found = read_rules(description, paths, rules, no_rules, diagnostics)
    system = name or system_name([str(p) for p in paths])
    timing = time_options(description, paths, time, diagnostics)
    package, built_root, _ = model_of(description, system, found, timing)
    root = root or built_root
    return Model(package, root, f"{system} ({root})", diagnostics.kept, description,
                 timing.platform if timing is not None else None)
