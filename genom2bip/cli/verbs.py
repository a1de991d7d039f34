"""The ``genom2bip`` command: one subcommand (verb) per job, each a single function.

A verb is added by writing ``def verb_x(args) -> int`` marked with
``@verb("x", help=..., arguments=...)``; ``arguments`` adds its options to
its argparse subparser.  Every verb gets errors the same way: diagnostics
(``file:line:column``, the source line, a caret) or any other
:class:`~runtime.errors.Genom2bipError` as a message on stderr and exit code 1
(:func:`exit_status`); bad usage exits 2; an unexpected exception is a bug,
reported on one "internal error" line with exit code 3 (``--traceback`` shows it).

This is the leaf of :mod:`genom2bip.cli`: exit codes, the ``@verb`` mark and
the argument helpers every verb shares.  It imports no other module of the
command line; each verb has a module of its own, listed by
:mod:`genom2bip.cli.command`.
"""
from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Sequence

from genom2bip.ir import Description
from genom2bip.loading import InputError, UsageError
from runtime.diagnostics import Diagnostic, DiagnosticError, SourceCache
from runtime.errors import Genom2bipError

from runtime.exits import (  # noqa: F401 - the one table (runtime/exits.py), shared with python -m runtime
    EXIT_CLOSED, EXIT_ERRORS, EXIT_INCONCLUSIVE, EXIT_INTERNAL, EXIT_INTERRUPTED, EXIT_OK, EXIT_USAGE, EXIT_VIOLATED,
)

#: The verb run when the first argument is not a verb (``genom2bip descriptions/dala -o gen/``).
DEFAULT_VERB = "generate"


@dataclass
class Verb:
    name: str
    help: str
    run: Callable[[argparse.Namespace], int]
    arguments: Callable[[argparse.ArgumentParser], None] | None


def verb(name: str, help: str, arguments: Callable[[argparse.ArgumentParser], None] | None = None):
    """Mark ``fn(args) -> exit code`` as the subcommand ``name``: ``fn.verb`` is its :class:`Verb`."""
    def mark(fn: Callable[[argparse.Namespace], int]) -> Callable[[argparse.Namespace], int]:
        fn.verb = Verb(name, help, fn, arguments)  # type: ignore[attr-defined]
        return fn
    return mark


class Failure(Genom2bipError):
    """Stops a verb with an exit code after its messages have been printed."""

    def __init__(self, code: int = EXIT_ERRORS) -> None:
        super().__init__(code)
        self.code = code


# --------------------------------------------------------------------------- shared helpers


def version() -> str:
    try:
        from importlib.metadata import version as dist_version
        return dist_version("genom2bip")
    except Exception:  # noqa: BLE001 - not installed: fall back to the package's own idea
        return getattr(sys.modules.get("genom2bip"), "__version__", "unknown")


def add_source_arguments(parser: argparse.ArgumentParser) -> None:
    """PATH... (files, or directories of .gen files), -I DIR, -D NAME[=VALUE]: what every reading verb takes."""
    parser.add_argument("paths", metavar="PATH", nargs="+",
                        help="description files (.gen), or directories whose .gen files are read")
    add_preprocessor_arguments(parser)


def add_preprocessor_arguments(parser: argparse.ArgumentParser) -> None:
    """-I DIR, -D NAME[=VALUE], as cpp takes them."""
    parser.add_argument("-I", dest="include_dirs", metavar="DIR", action="append", default=[],
                        help="add DIR to the #include search path")
    parser.add_argument("-D", dest="defines", metavar="NAME[=VALUE]", action="append", default=[],
                        help="define a preprocessor macro (VALUE defaults to 1)")


def description_files(paths: Sequence[str]) -> list[Path]:
    """Expand directories into their description files (sorted); missing paths are reported."""
    from genom2bip.loading import description_files as files

    return files(paths)


def parse_defines(items: Sequence[str]) -> dict[str, str]:
    defines: dict[str, str] = {}
    for item in items:
        name, _, value = item.partition("=")
        if not name.isidentifier():
            error(f"-D {item}: '{name}' is not a macro name")
            raise Failure(EXIT_USAGE)
        defines[name] = value if _ else "1"
    return defines


def error(message: str) -> None:
    print(f"genom2bip: error: {message}", file=sys.stderr)


def print_diagnostics(diagnostics: Sequence[Diagnostic], sources: SourceCache | None) -> None:
    """All diagnostics sorted by location, errors counted at the end."""
    ordered = sorted(diagnostics, key=lambda d: (d.span.file, d.span.line, d.span.column))
    for diag in ordered:
        print(diag.render(sources), file=sys.stderr)
    n = sum(1 for d in ordered if d.severity == "error")
    if n > 1:
        print(f"{n} errors", file=sys.stderr)


def load(args: argparse.Namespace, check: bool = True) -> Description:
    """Parse (and check) the descriptions named on the command line; print problems and fail on errors."""
    from genom2bip.loading import Diagnostics, read_description

    files = description_files(args.paths)
    defines = parse_defines(args.defines)
    return read_description(files, defines, args.include_dirs, check, Diagnostics(print_diagnostics))


def rules_file(args: argparse.Namespace) -> Path | None:
    """``--rules FILE``; else, when descriptions are given as a directory, its ``rules.yaml`` (``--no-rules``: none)."""
    from genom2bip.loading import rule_file

    return rule_file(args.paths, getattr(args, "rules", None), getattr(args, "no_rules", False))


def load_rules(args: argparse.Namespace, description: Description) -> list:
    """The description's constraints plus the rule file's; print problems and fail on errors."""
    from genom2bip.loading import Diagnostics, read_rules

    return read_rules(description, args.paths, getattr(args, "rules", None), getattr(args, "no_rules", False),
                      Diagnostics(print_diagnostics))


def add_rules_arguments(parser: argparse.ArgumentParser) -> None:
    """--rules FILE / --no-rules: what every verb that builds a model takes."""
    parser.add_argument("--rules", metavar="FILE",
                        help="rules between services (YAML, docs/rules.md); default: rules.yaml in the directory given")
    parser.add_argument("--no-rules", action="store_true",
                        help="only the descriptions' own constraints, no rule file")


def exit_status(exc: Genom2bipError) -> int:
    """The one place where the product's errors become an exit status (and a message, unless already printed)."""
    if isinstance(exc, Failure):
        return exc.code
    if isinstance(exc, InputError):  # its diagnostics, if any, were printed as they were found
        for message in exc.messages:
            error(message)
        for group in exc.groups:
            print_diagnostics(group.diagnostics, group.sources)
        return EXIT_USAGE if isinstance(exc, UsageError) else EXIT_ERRORS
    if isinstance(exc, DiagnosticError):  # a verb that let its input's problems through
        print_diagnostics(exc.diagnostics, exc.sources)
        return EXIT_ERRORS
    error(str(exc))
    return EXIT_ERRORS


def load_externs(spec: str | None) -> dict[str, Any]:
    """``--externs MODULE``: the public names of that Python module, binding extern functions that are not codels."""
    from genom2bip.verify.search import extern_bindings
    from runtime.engine.errors import EngineError

    try:
        return extern_bindings(spec)
    except EngineError as exc:
        error(str(exc))
        raise Failure(EXIT_ERRORS) from None
