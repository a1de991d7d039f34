"""Reading an input file as UTF-8 text, with a located error when it is not text.

Rule files, property files and ``.bip`` files are read with this, so that a
binary or mis-encoded file is an input error at the first undecodable byte
(``file:line:column``), not an internal error.
"""
from __future__ import annotations

from pathlib import Path

from runtime.diagnostics import Diagnostic, DiagnosticError, SourceCache, Span


def decode_error(file: str, data: bytes, err: UnicodeDecodeError) -> Diagnostic:
    """Where in ``data`` decoding stopped, as a diagnostic with the line quoted."""
    line_start = data.rfind(b"\n", 0, err.start) + 1
    line = data.count(b"\n", 0, err.start) + 1
    column = len(data[line_start:err.start].decode("utf-8", errors="replace")) + 1
    line_end = data.find(b"\n", err.start)
    quoted = data[line_start:line_end if line_end >= 0 else len(data)].decode("utf-8", errors="replace")
    return Diagnostic(Span(file, line, column), f"not a UTF-8 text file: byte 0x{data[err.start]:02x} cannot be read",
                      hint="the file is binary, or saved in another encoding: save it as UTF-8 text",
                      source_line="".join(ch if ch.isprintable() or ch == "\t" else "?" for ch in quoted[:200]))


def read_text(path: str | Path, what: str) -> str:
    """The text of ``path``; a DiagnosticError naming ``what`` (e.g. "rule file") when it cannot be read as UTF-8."""
    file = str(path)
    if Path(path).exists() and not Path(path).is_file():
        raise DiagnosticError([Diagnostic(Span(file, 0, 0), f"cannot read the {what}: not a regular file")])
    try:
        data = Path(path).read_bytes()
    except OSError as err:
        raise DiagnosticError(
            [Diagnostic(Span(file, 0, 0), f"cannot read the {what}: {err.strerror or err}")]
        ) from None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise DiagnosticError([decode_error(file, data, err)], SourceCache()) from None
