"""``genom2bip graph MODEL``: pictures of the model — the functional level, one module, one atom.

MODEL is description files or directories (built as ``generate`` builds them,
rules included) or one ``.bip`` file.  The picture is written in the format
the output's suffix names (``.dot``, ``.svg``, ``.png``), or printed as DOT.
"""
from __future__ import annotations

import argparse
import difflib
import sys

from genom2bip.cli.verbs import (
    EXIT_ERRORS,
    EXIT_OK,
    Failure,
    add_preprocessor_arguments,
    add_rules_arguments,
    error,
    verb,
)


def _arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("paths", metavar="MODEL", nargs="+",
                        help="one .bip file, or description files (.gen) / directories of them")
    add_preprocessor_arguments(parser)
    parser.add_argument("--root", help="root instance of a .bip model (default: the last compound type)")
    add_rules_arguments(parser)
    parser.add_argument("--name", metavar="SYSTEM", help="system name when building from descriptions")
    what = parser.add_mutually_exclusive_group()
    what.add_argument("--module", metavar="NAME", help="one module as a compound, with its connectors (paper Fig. 7)")
    what.add_argument("--atom", metavar="PATH", help="one atom as an automaton, e.g. NDD.GoTo.activity (Fig. 3)")
    what.add_argument("--list", action="store_true", help="list the modules and atoms that can be drawn")
    parser.add_argument(
        "-o", "--output", metavar="FILE", help="write FILE (.dot, .svg or .png); default: DOT on stdout"
    )


def load_structure(args: argparse.Namespace):
    """(flat system, structure) of the model the arguments name."""
    from runtime.engine import EngineError, flatten
    from runtime.pictures import structure

    interface = None
    if len(args.paths) == 1 and args.paths[0].endswith(".bip"):
        from genom2bip.cli.verify import load_model

        model = load_model(args)
        package, root, title = model.package, model.root, model.title
    else:
        from genom2bip.back.interface import interface_data
        from genom2bip.cli.verbs import load, load_rules
        from genom2bip.generate import GenerateError, model_of, system_name

        description = load(args)
        rules = load_rules(args, description)
        system = args.name or system_name(args.paths)
        try:
            package, root, _ = model_of(description, system, rules)
        except GenerateError as exc:
            error(str(exc))
            raise Failure(EXIT_ERRORS) from None
        root = args.root or root
        title = f"{system} ({root})"
        interface = interface_data(description, system, " ".join(args.paths))
    try:
        flat = flatten(package, root)
    except EngineError as exc:
        error(f"{title}: {exc}")
        raise Failure(EXIT_ERRORS) from None
    return flat, structure(flat, interface)


def _unknown(what: str, name: str, known: list[str]) -> None:
    close = difflib.get_close_matches(name, known, n=3)
    hint = f"; did you mean {', '.join(close)}?" if close else f"; known: {', '.join(known[:12])}" + \
        (" …" if len(known) > 12 else "")
    error(f"no {what} named {name!r}{hint}")
    raise Failure(EXIT_ERRORS)


@verb("graph", help="pictures of the model: the functional level, one module (--module), one atom (--atom)",
      arguments=_arguments)
def verb_graph(args: argparse.Namespace) -> int:
    """Draw the view asked for and write it (or print its DOT text)."""
    from runtime.pictures import PictureError, automaton, functional_level, module, render

    flat, s = load_structure(args)
    if args.list:
        print("modules: " + (", ".join(s.modules) or "(none)"))
        print("atoms:")
        for name, type_name in s.atoms.items():
            print(f"  {name}: {type_name}")
        return EXIT_OK
    if args.module:
        if args.module not in s.modules:
            _unknown("module", args.module, s.modules)
        text = module(s, args.module)
    elif args.atom:
        if args.atom not in s.atoms:
            _unknown("atom", args.atom, list(s.atoms))
        text = automaton(flat, args.atom)
    else:
        text = functional_level(s)
    if not args.output:
        sys.stdout.write(text)
        return EXIT_OK
    try:
        render(text, args.output)
    except PictureError as exc:
        error(str(exc))
        return EXIT_ERRORS
    print(f"wrote {args.output}")
    return EXIT_OK
