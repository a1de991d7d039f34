"""The root of every error the product reports to its user.

Front end, generator, engine and explorer errors all derive from
:class:`Genom2bipError`, so that a command line catches one class and maps it
to an exit status in one place (``genom2bip.cli.verbs``), and anything else is a
bug.  It lives in ``runtime`` because the runtime never imports the generator.
"""
from __future__ import annotations


class Genom2bipError(Exception):
    """Something the user can fix (an input, an option, the model): reported as a message, not a traceback."""
