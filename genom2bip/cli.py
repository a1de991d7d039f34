"""The ``genom2bip`` command: one subcommand (verb) per job, each a single function.

A verb is added by writing ``def verb_x(args) -> int`` decorated with
``@verb("x", help=..., arguments=...)``; ``arguments`` adds its options to
its argparse subparser.  Every verb gets errors the same way: diagnostics
(``file:line:column``, the source line, a caret) or any other
:class:`~runtime.errors.Genom2bipError` as a message on stderr and exit code 1
(:func:`exit_status`); bad usage exits 2; an unexpected exception is a bug,
reported on one "internal error" line with exit code 3 (``--traceback`` shows it).
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Sequence

from genom2bip.ir import Description
from runtime.diagnostics import Diagnostic, DiagnosticError, Reporter, SourceCache
from runtime.errors import Genom2bipError

EXIT_OK, EXIT_ERRORS, EXIT_USAGE, EXIT_INTERNAL = 0, 1, 2, 3

#: The verb run when the first argument is not a verb (``genom2bip descriptions/dala -o gen/``).
DEFAULT_VERB = "generate"

DESCRIPTION_SUFFIXES = (".gen",)


@dataclass
class Verb:
    name: str
    help: str
    run: Callable[[argparse.Namespace], int]
    arguments: Callable[[argparse.ArgumentParser], None] | None


VERBS: dict[str, Verb] = {}


def verb(name: str, help: str, arguments: Callable[[argparse.ArgumentParser], None] | None = None):
    """Register ``fn(args) -> exit code`` as the subcommand ``name``."""
    def register(fn: Callable[[argparse.Namespace], int]) -> Callable[[argparse.Namespace], int]:
        VERBS[name] = Verb(name, help, fn, arguments)
        return fn
    return register


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
    files: list[Path] = []
    missing: list[str] = []
    for raw in paths:
        path = Path(raw)
        if path.is_dir():
            found = sorted(p for p in path.iterdir() if p.suffix in DESCRIPTION_SUFFIXES and p.is_file())
            if not found:
                error(f"{raw}: no {'/'.join(DESCRIPTION_SUFFIXES)} file in this directory")
                missing.append(raw)
            files.extend(found)
        elif path.exists() and not path.is_file():
            error(f"{raw}: not a regular file (a device or a pipe cannot be read as a description)")
            missing.append(raw)
        elif path.exists():
            files.append(path)
        else:
            error(f"{raw}: no such file or directory")
            missing.append(raw)
    if missing:
        raise Failure(EXIT_ERRORS)
    return files


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
    files = description_files(args.paths)
    defines = parse_defines(args.defines)
    from genom2bip.checks import check_description
    from genom2bip.parser import parse_paths

    reporter = Reporter()  # the parsers' warnings, then the checks' diagnostics
    try:
        description = parse_paths([str(f) for f in files], include_dirs=tuple(args.include_dirs), defines=defines,
                                  reporter=reporter)
    except DiagnosticError as exc:
        print_diagnostics(exc.diagnostics, exc.sources)
        raise Failure(EXIT_ERRORS) from None
    if not check and reporter.diagnostics:
        print_diagnostics(reporter.diagnostics, reporter.sources)
    if check:
        check_description(description, reporter)
        if reporter.diagnostics:
            print_diagnostics(reporter.diagnostics, reporter.sources)
        if reporter.has_errors:
            raise Failure(EXIT_ERRORS)
    return description


def rules_file(args: argparse.Namespace) -> Path | None:
    """``--rules FILE``; else, when descriptions are given as a directory, its ``rules.yaml``.

    A single description file does not pick up the rule file beside it: that
    file names the other modules of the system (verify one module alone).
    ``--no-rules`` keeps only the descriptions' own constraints.
    """
    if getattr(args, "no_rules", False):
        return None
    if getattr(args, "rules", None):
        return Path(args.rules)
    first = Path(args.paths[0])
    default = first / "rules.yaml"
    return default if first.is_dir() and default.is_file() else None


def load_rules(args: argparse.Namespace, description: Description) -> list:
    """The description's constraints plus the rule file's; print problems and fail on errors."""
    from genom2bip.rules import all_rules

    reporter = Reporter()
    path = rules_file(args)
    if path is not None and args.rules and not path.is_file():
        error(f"{args.rules}: no such rule file")
        raise Failure(EXIT_ERRORS)
    rules = all_rules(description, path, reporter)
    if reporter.diagnostics:
        print_diagnostics(reporter.diagnostics, reporter.sources)
    if reporter.has_errors:
        raise Failure(EXIT_ERRORS)
    return rules


# --------------------------------------------------------------------------- verbs


def _check_arguments(parser: argparse.ArgumentParser) -> None:
    add_source_arguments(parser)
    parser.add_argument("--json", action="store_true", help="print the description IR as JSON instead of a summary")


@verb("check", help="parse and check descriptions; print a summary of each component", arguments=_check_arguments)
def verb_check(args: argparse.Namespace) -> int:
    """Parse, check, and print what each component contains (or the IR as JSON)."""
    from genom2bip.ir import to_json
    from genom2bip.summary import description_summary

    description = load(args)
    if args.json:
        json.dump(to_json(description), sys.stdout, indent=2, default=str)
        sys.stdout.write("\n")
    else:
        print(description_summary(description))
    return EXIT_OK


def _generate_arguments(parser: argparse.ArgumentParser) -> None:
    add_source_arguments(parser)
    parser.add_argument("-o", "--output", metavar="DIR", default="gen",
                        help="directory to write <system>/ into (default: gen)")
    parser.add_argument("--name", metavar="SYSTEM",
                        help="name of the system (default: the first PATH's name, e.g. dala)")
    add_rules_arguments(parser)
    from genom2bip.verify_timed import add_time_arguments
    add_time_arguments(parser)


def add_rules_arguments(parser: argparse.ArgumentParser) -> None:
    """--rules FILE / --no-rules: what every verb that builds a model takes."""
    parser.add_argument("--rules", metavar="FILE",
                        help="rules between services (YAML, docs/rules.md); default: rules.yaml in the directory given")
    parser.add_argument("--no-rules", action="store_true",
                        help="only the descriptions' own constraints, no rule file")


@verb("generate", help="generate the BIP model (.bip) and a runnable Python package (the default command)",
      arguments=_generate_arguments)
def verb_generate(args: argparse.Namespace) -> int:
    """Parse, check, build the BIP model and write ``<output>/<system>/`` atomically."""
    from genom2bip.generate import GenerateError, generate, system_name

    if not args.output:
        error("-o: give a directory (an empty name would write into the current directory)")
        return EXIT_USAGE
    description = load(args)
    rules = load_rules(args, description)
    system = args.name or system_name(args.paths)
    sources = " ".join(args.paths) + (f" --rules {args.rules}" if args.rules else "")
    from genom2bip.verify_timed import time_options, warn_untimed
    time = time_options(args, description)
    sources += (" --timed" if time.ticks else " --monitor") if time is not None else ""
    try:
        inputs = [*args.paths, *args.include_dirs, *([str(rules_file(args))] if rules_file(args) else [])]
        result = generate(description, system, Path(args.output), sources, version(), rules, inputs, time)
    except DiagnosticError as exc:
        print(exc.render(), file=sys.stderr)
        return EXIT_ERRORS
    except GenerateError as exc:
        error(str(exc))
        return EXIT_ERRORS
    except OSError as exc:
        error(f"cannot write {args.output}: {exc.strerror or exc}")
        return EXIT_ERRORS
    warn_untimed(result.package)
    print(f"generated {result.directory}/ ({len(result.files)} files): root {result.root}, "
          f"{len(result.package.atom_types)} atom types, {len(result.package.connector_types)} connector types")
    kept = [name for name in result.kept if name != "__pycache__"]  # Python's cache of the package: not news
    if kept:
        print(f"kept in {result.directory}/, not written by genom2bip: {', '.join(kept)}")
    for path in result.leftovers:
        print(f"genom2bip: warning: {path}/ was left by an interrupted run and holds files genom2bip did not "
              f"write; it is kept", file=sys.stderr)
    return EXIT_OK


# --------------------------------------------------------------------------- entry point


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="genom2bip",
        description="GenoM module descriptions to BIP component models: check, generate, run, verify.")
    parser.add_argument("--version", action="version", version=f"%(prog)s {version()}")
    parser.add_argument("--traceback", action="store_true",
                        help="on an internal error, print the whole traceback (also GENOM2BIP_TRACEBACK=1)")
    sub = parser.add_subparsers(dest="verb", metavar="COMMAND")
    sub.required = True
    for v in VERBS.values():
        p = sub.add_parser(v.name, help=v.help, description=v.help)
        if v.arguments is not None:
            v.arguments(p)
        p.set_defaults(run=v.run)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit code (0 ok, 1 errors in the input, 2 usage, 3 internal error)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    show_traceback = "--traceback" in argv or os.environ.get("GENOM2BIP_TRACEBACK", "") not in ("", "0")
    argv = [a for a in argv if a != "--traceback"]
    for stream in (sys.stdout, sys.stderr):  # a file name the terminal cannot show is escaped, not a crash
        if hasattr(stream, "reconfigure"):
            stream.reconfigure(errors="backslashreplace")
    parser = build_parser()
    if argv and not argv[0].startswith("-") and argv[0] not in VERBS and DEFAULT_VERB in VERBS:
        if not Path(argv[0]).exists():
            parser.print_usage(sys.stderr)
            error(f"'{argv[0]}' is neither a command ({', '.join(VERBS)}) nor a file or directory")
            return EXIT_USAGE
        argv.insert(0, DEFAULT_VERB)
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse: --help, --version, usage errors
        return int(exc.code) if isinstance(exc.code, int) else EXIT_USAGE
    try:
        return args.run(args)
    except Genom2bipError as exc:
        return exit_status(exc)
    except KeyboardInterrupt:
        print("genom2bip: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return EXIT_OK
    except Exception as exc:  # noqa: BLE001 - the last resort: one line, the traceback only when asked for
        if show_traceback:
            traceback.print_exc()
        print(f"genom2bip: internal error: {type(exc).__name__}: {exc}", file=sys.stderr)
        if not show_traceback:
            print("genom2bip: run again with --traceback (or GENOM2BIP_TRACEBACK=1) to see where", file=sys.stderr)
        return EXIT_INTERNAL


def exit_status(exc: Genom2bipError) -> int:
    """The one place where the product's errors become an exit status (and a message, unless already printed)."""
    if isinstance(exc, Failure):
        return exc.code
    if isinstance(exc, DiagnosticError):  # a verb that let its input's problems through
        print_diagnostics(exc.diagnostics, exc.sources)
        return EXIT_ERRORS
    error(str(exc))
    return EXIT_ERRORS


def entry_point() -> None:
    """Console-script wrapper: exit with main()'s code."""
    sys.exit(main())


if __name__ == "__main__":
    entry_point()
from genom2bip import call_cli  # noqa: E402,F401 - registers the call verb
from genom2bip import verify_cli  # noqa: F401,E402
from genom2bip import graph_cli  # noqa: F401,E402
from genom2bip import mission_cli  # noqa: F401,E402 - registers the mission verb
