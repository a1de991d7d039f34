"""The exit statuses of every command (``genom2bip``, ``python -m runtime``, ``python -m <generated package>``).

One table, one meaning per number, so that a script reads any of them the same way: 0 the answer is yes (or the
run ended as asked), 4 the answer is no (something was found), 5 no answer yet.  It lives in the runtime because
the runtime's own command line uses it and must not import the generator; ``genom2bip`` imports it from here.
"""
from __future__ import annotations

EXIT_OK = 0
EXIT_ERRORS = 1
EXIT_USAGE = 2
EXIT_INTERNAL = 3
EXIT_VIOLATED = 4
EXIT_INCONCLUSIVE = 5
EXIT_INTERRUPTED = 130
EXIT_CLOSED = 141

#: (status, meaning), in the order ``--help`` and the README show them.
TABLE: tuple[tuple[int, str], ...] = (
    (EXIT_OK, "done: every check holds, every expectation met, the run ended as asked"),
    (EXIT_ERRORS, "errors in the input (file:line:column) or an input that cannot be used; nothing written"),
    (EXIT_USAGE, "bad usage: an unknown option or a missing argument"),
    (EXIT_INTERNAL, "internal error: a bug (one line; --traceback or GENOM2BIP_TRACEBACK=1 shows where)"),
    (EXIT_VIOLATED, "found: a deadlock, a violated property or invariant, a model error, an unmet expectation, "
                    "real time not held"),
    (EXIT_INCONCLUSIVE, "inconclusive: a limit (states, time, memory) stopped the search before an answer, "
                        "or no trace shows the answer"),
    (EXIT_INTERRUPTED, "interrupted by Ctrl-C (or SIGTERM), after saying what was known"),
    (EXIT_CLOSED, "stopped because nobody reads the output any more (a campaign piped into head)"),
)


def epilog() -> str:
    """The table as the last paragraph of a ``--help`` (argparse.RawDescriptionHelpFormatter keeps its lines)."""
    return "exit status:\n" + "\n".join(f"  {code:>3}  {meaning}" for code, meaning in TABLE)


def closed_output() -> int:
    """stdout's reader went away (``| head``): what is left to print goes nowhere, no traceback; EXIT_CLOSED."""
    import os
    import sys

    try:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    except (OSError, ValueError):
        pass
    return EXIT_CLOSED
