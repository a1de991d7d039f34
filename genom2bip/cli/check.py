"""``genom2bip check PATH...``: parse and check descriptions, print a summary of each component (or JSON)."""
from __future__ import annotations

import argparse
import json
import sys

from genom2bip.cli.verbs import EXIT_OK, add_rules_arguments, add_source_arguments, load, load_rules, rules_file, verb


def _check_arguments(parser: argparse.ArgumentParser) -> None:
    add_source_arguments(parser)
    add_rules_arguments(parser)
    parser.add_argument("--json", action="store_true", help="print the description IR as JSON instead of a summary")


@verb("check", help="parse and check descriptions; print a summary of each component", arguments=_check_arguments)
def verb_check(args: argparse.Namespace) -> int:
    """Parse, check, and print what each component contains (or the IR as JSON).

    A description without any component is valid, as for genom3 (an IDL file):
    the summary says so. The rule file of a directory is read and checked too.
    """
    from genom2bip.ir import to_json
    from genom2bip.summary import description_summary

    description = load(args)
    rules = load_rules(args, description) if description.components else []
    if args.json:
        json.dump(to_json(description), sys.stdout, indent=2, default=str)
        sys.stdout.write("\n")
    else:
        print(description_summary(description))
        path = rules_file(args)
        if path is not None and description.components:
            from_file = sum(1 for r in rules if r.origin == "rules")
            print(f"\nrules: {from_file} from {path}, {len(rules) - from_file} from the descriptions' own constraints")
    return EXIT_OK
