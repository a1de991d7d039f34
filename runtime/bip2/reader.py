"""Read BIP2 text into a runtime.model Package: parse, build, fill export types, check names."""
from __future__ import annotations

from pathlib import Path

from lark import Tree

from runtime.bip2.builder import Builder
from runtime.bip2.interfaces import resolve_export_types
from runtime.bip2.locator import Locator
from runtime.bip2.syntax import parse_tree
from runtime.bip2.validate import validate
from runtime.diagnostics import DiagnosticError, Reporter, SourceCache, Span
from runtime.model import Package
from runtime.nesting import MAX_DEPTH, too_deep
from runtime.textfile import decode_error


def parse_text(text: str, filename: str = "<string>") -> Package:
    """The package written in ``text``; raises DiagnosticError listing every problem found."""
    sources = SourceCache()
    sources.add(filename, text)
    reporter = Reporter(sources)
    package = _read(text, filename, reporter)
    reporter.raise_if_errors()
    return package


def parse_file(path) -> Package:
    """The package in the file ``path``, which must be named after the package (``P.bip`` holds ``package P``)."""
    path = Path(path)
    filename = str(path)
    sources = SourceCache()
    reporter = Reporter(sources)
    try:
        if path.exists() and not path.is_file():  # a device or a FIFO: reading it would never end or never start
            reporter.error(Span(filename, 0, 0), "cannot read BIP2 file: not a regular file (a device, a pipe or "
                                                 "a directory)")
            reporter.raise_if_errors()
        data = path.read_bytes()
    except OSError as err:
        reporter.error(Span(filename, 0, 0), f"cannot read BIP2 file: {err}")
        reporter.raise_if_errors()
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise DiagnosticError([decode_error(filename, data, err)]) from None
    sources.add(filename, text)
    package = _read(text, filename, reporter)
    if package is not None and path.suffix == ".bip" and package.name != path.stem:
        reporter.error(package.span, f"package '{package.name}' must be in a file named {package.name}.bip, "
                                     f"not {path.name}")
    reporter.raise_if_errors()
    return package


def _read(text: str, filename: str, reporter: Reporter) -> Package | None:
    tree = parse_tree(text, filename)
    if not isinstance(tree, Tree):
        reporter.diagnostics.append(tree)
        return None
    deep = too_deep(tree)
    if deep is not None:
        meta = deep.meta
        reporter.error(Span(filename, getattr(meta, "line", 1), getattr(meta, "column", 1)),
                       f"nested more than {MAX_DEPTH} operators deep here")
        return None
    locator = Locator()
    package = Builder(filename, text, reporter, locator).transform(tree)
    resolve_export_types(package)
    validate(package, locator, reporter)
    _drop_repeats(reporter)
    return package


def _drop_repeats(reporter: Reporter) -> None:
    """One report per place and message: ``component B a(), b()`` names the unknown B once."""
    seen, kept = set(), []
    for d in reporter.diagnostics:
        key = (d.span, d.message)
        if key not in seen:
            seen.add(key)
            kept.append(d)
    reporter.diagnostics[:] = kept
