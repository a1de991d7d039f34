"""Properties of BIP models: an MCL-style regular alternation-free mu-calculus, pattern shorthands, checking.

``read_properties(text, file, flat)`` gives checkable properties (static
errors as ``DiagnosticError`` with ``file:line:column``); ``check(space, p)``
answers one on a :class:`~runtime.explore.space.StateSpace` with a witness or
a counterexample.  docs/verification/properties.md is the language reference.
"""
from runtime.props.check import (
    Checkable,
    Verdict,
    check,
    describe,
    read_properties,
    read_property_file,
    read_property_text,
)

__all__ = ["Checkable", "Verdict", "check", "describe", "read_properties", "read_property_file", "read_property_text"]
