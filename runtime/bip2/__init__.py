"""BIP2 text in: the Verimag BIP2 language (untimed) read into runtime.model objects, with checks.

This package must not import genom2bip: the runtime reads .bip files on its own.
"""
from runtime.bip2.reader import parse_file, parse_text
from runtime.bip2.reserved import RESERVED, is_identifier
from runtime.bip2.validate import validate

__all__ = ["RESERVED", "is_identifier", "parse_file", "parse_text", "validate"]
