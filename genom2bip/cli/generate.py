"""``genom2bip generate PATH... -o DIR`` (the default verb): the BIP model and a runnable Python package."""
from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from genom2bip.cli.verbs import (
    EXIT_ERRORS, EXIT_OK, EXIT_USAGE, add_rules_arguments, add_source_arguments, error, load, load_rules,
    print_diagnostics, rules_file, verb, version,
)
from runtime.diagnostics import DiagnosticError


def _generate_arguments(parser: argparse.ArgumentParser) -> None:
    add_source_arguments(parser)
    parser.add_argument("-o", "--output", metavar="DIR", default="gen",
                        help="directory to write <system>/ into (default: gen)")
    parser.add_argument("--name", metavar="SYSTEM",
                        help="name of the system (default: the first PATH's name, e.g. dala)")
    parser.add_argument("--c-codels", metavar="DIR",
                        help="C/C++ codels to compile, DIR/<Component>/ per component (default: each component's "
                             "codels/ folder beside its .gen; docs/codels.md)")
    add_rules_arguments(parser)
    from genom2bip.cli.verify_timed import add_time_arguments
    add_time_arguments(parser)


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
    sources += f" --c-codels {args.c_codels}" if args.c_codels else ""
    from genom2bip.cli.verify_timed import time_settings, warn_untimed
    from genom2bip.loading import Diagnostics, time_options
    time = time_options(description, args.paths, time_settings(args), Diagnostics(print_diagnostics))
    sources += (" --timed" if time.ticks else " --monitor") if time is not None else ""
    if args.c_codels and not Path(args.c_codels).is_dir():
        error(f"--c-codels {args.c_codels}: no such directory")
        return EXIT_ERRORS
    try:
        inputs = [*args.paths, *args.include_dirs, *([str(rules_file(args))] if rules_file(args) else [])]
        result = generate(description, system, Path(args.output), sources, version(), rules, inputs, time,
                          c_codels=Path(args.c_codels) if args.c_codels else None)
    except DiagnosticError as exc:
        print(exc.render(), file=sys.stderr)
        return EXIT_ERRORS
    except GenerateError as exc:
        error(str(exc))
        return EXIT_ERRORS
    except OSError as exc:
        name = os.path.basename(str(exc.filename or ""))
        writing = f" (writing {name})" if name and ".new." not in name and ".old." not in name else ""
        error(f"cannot write {args.output}: {exc.strerror or exc}{writing}; {args.output} is left as it was")
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
