"""Reading GenoM descriptions: files or text in, one :class:`Description` out, or every error at once.

Each file is preprocessed (``preprocess``), its dialect detected
(:func:`detect_dialect`) and handed to the GenoM3 dotgen front end (``dotgen``)
or the GenoM2 one (``genom2``).  Diagnostics of all files are collected in one
:class:`Reporter`; if any is an error a :class:`DiagnosticError` carrying all of
them is raised and no half-built description escapes.
"""
from __future__ import annotations

import re
from pathlib import Path
from typing import Mapping, Sequence

from genom2bip.ir import Description
from genom2bip.parser.preprocess import Preprocessed, preprocess
from runtime.diagnostics import Reporter, Span

__all__ = ["parse_paths", "parse_text", "detect_dialect", "preprocess", "Preprocessed"]

_COMMENT_OR_STRING = re.compile(r'/\*.*?\*/|//[^\n]*|"[^"\\\n]*(?:\\.[^"\\\n]*)*"|\'[^\'\\\n]*(?:\\.[^\'\\\n]*)*\'',
                                re.S)
_GENOM3 = re.compile(r"(?:^|[;}])\s*(?:component|interface)\s+[A-Za-z_]\w*\s*[{;]")
_GENOM2_BLOCK = re.compile(r"(?:^|[;}])\s*(?:request|exec_task|poster)\s+[A-Za-z_]\w*\s*\{")
_GENOM2_MODULE = re.compile(r"(?:^|[;}])\s*module\s+[A-Za-z_]\w*\s*\{\s*[A-Za-z_]\w*\s*:")


def detect_dialect(text: str) -> str:
    """``"genom3"`` or ``"genom2"``, from the shape of the top-level declarations.

    The rule, applied to the text without comments and string literals:

    1. a ``component NAME {`` or ``interface NAME {`` (or ``... ;``) declaration
       means GenoM3;
    2. otherwise a GenoM2 block, ``request|exec_task|poster NAME {``, or a
       ``module NAME {`` whose body starts with a ``field:`` (GenoM2 modules are
       lists of ``name: value;`` fields, IDL modules hold declarations) means
       GenoM2;
    3. anything else (IDL types and constants only, or an empty file) is read as
       GenoM3, whose IDL subset it is.
    """
    bare = _COMMENT_OR_STRING.sub(lambda m: " " if m.group().startswith("/") else '""', text)
    bare = re.sub(r"^[ \t]*#[^\n]*", "", bare, flags=re.M)
    if _GENOM3.search(bare):
        return "genom3"
    if _GENOM2_BLOCK.search(bare) or _GENOM2_MODULE.search(bare):
        return "genom2"
    return "genom3"


def _front_end(dialect: str, source: Preprocessed, reporter: Reporter, description: Description) -> None:
    if dialect == "genom3":
        from genom2bip.parser.dotgen import parse_dotgen

        parse_dotgen(source, reporter, description)
        return
    try:
        from genom2bip.parser.genom2 import parse_genom2
    except ModuleNotFoundError as exc:
        if exc.name not in ("genom2bip.parser.genom2",):
            raise
        reporter.error(source.span(1, 1), "GenoM2 support not available",
                       hint="this file uses the GenoM2 syntax (module/request/exec_task/poster)")
        return
    parse_genom2(source, reporter, description)


def _parse_one(
    text_or_path: str | Path,
    filename: str,
    reporter: Reporter,
    description: Description,
    include_dirs: Sequence[str],
    defines: Mapping[str, str] | None,
) -> None:
    source = preprocess(text_or_path, filename=filename, include_dirs=include_dirs, defines=defines, reporter=reporter)
    if source is None:
        return
    dialect = detect_dialect(source.text)
    _front_end(dialect, source, reporter, description)


def parse_paths(
    paths: list[str | Path],
    include_dirs: Sequence[str] = (),
    defines: Mapping[str, str] | None = None,
    reporter: Reporter | None = None,
) -> Description:
    """Parse files and directories (every ``*.gen`` in a directory, sorted) into one description.

    Raises :class:`DiagnosticError` with every diagnostic if any of them is an error.
    Warnings stay in ``reporter`` when one is given (the caller prints them).
    """
    reporter = reporter if reporter is not None else Reporter()
    description = Description()
    files: list[Path] = []
    for p in paths:
        path = Path(p)
        if path.is_dir():
            found = sorted(path.glob("*.gen"))
            if not found:
                reporter.error(Span(str(path), 1, 1), f"no .gen file in directory '{path}'")
            files.extend(found)
        elif path.exists():
            files.append(path)
        else:
            reporter.error(Span(str(path), 1, 1), f"no such file or directory: '{path}'")
    for f in files:
        _parse_one(f, str(f), reporter, description, include_dirs, defines)
    reporter.raise_if_errors()
    return description


def parse_text(
    text: str,
    filename: str = "<string>",
    include_dirs: Sequence[str] = (),
    defines: Mapping[str, str] | None = None,
) -> Description:
    """Parse a description given as text (tests, tools); ``filename`` names it in messages and for includes."""
    reporter = Reporter()
    description = Description()
    _parse_one(text, filename, reporter, description, include_dirs, defines)
    reporter.raise_if_errors()
    return description
