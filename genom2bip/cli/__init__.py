"""The ``genom2bip`` command line: one module per verb, a leaf module they share, and the command that lists them.

``verbs`` (exit codes, the ``@verb`` mark, argument helpers) imports no other
module here; ``check``, ``generate``, ``call``, ``verify`` (with its engines
``verify_native``, ``verify_spin``, ``verify_compositional``, ``verify_timed``),
``graph`` and ``mission`` are the verbs (``verify`` prints what the verification API,
:mod:`genom2bip.verify`, returns); ``printers`` prints traces and states;
``command`` builds the parser and runs a verb.
"""
from __future__ import annotations

from typing import Sequence


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line (:func:`genom2bip.cli.command.main`); the verbs are imported only when it runs."""
    from genom2bip.cli.command import main as run

    return run(argv)
