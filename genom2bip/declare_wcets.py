"""Declared WCETs rewritten in the descriptions' own text: ``wcet N ms`` set on named codels, found by the parser.

A codel is named as the codel times name it (runtime.controller.codel_times): ``Module.Owner.codel``, the
owner being its service or its task.  The parser gives where each codel's name is; its declaration ends at the
next ``;`` outside a comment.  An existing ``wcet`` there is replaced, else one is added before the ``;``;
nothing else of the file changes (comments, layout).  The new texts are parsed again, in a copy of the
descriptions' folders, and each codel must read back with the WCET asked before a file is written.
"""
from __future__ import annotations

import re
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping, Sequence

from genom2bip import ir
from genom2bip.loading import read_description
from genom2bip.output import write_file
from runtime.diagnostics import Span
from runtime.errors import Genom2bipError

_WCET = re.compile(r"\bwcet\b")


class WcetEditError(Genom2bipError):
    """A WCET cannot be set: the codel is not in the descriptions, or its declaration cannot be read."""


@dataclass
class Place:
    """Where a codel is declared: the span of its name, and what it declares now (s, None: no wcet)."""

    span: Span
    seconds: float | None


def codels(description: ir.Description) -> dict[str, Place]:
    """Every codel of the description by ``Module.Owner.codel`` (validate codels too), with where it is declared."""
    out: dict[str, Place] = {}
    for comp in description.components:
        owned = [(t.name, t.codels) for t in comp.tasks]
        owned += [(s.name, ([s.validate] if s.validate else []) + s.codels) for s in comp.services]
        for owner, listed in owned:
            for codel in listed:
                out[f"{comp.name}.{owner}.{codel.name}"] = Place(codel.span, codel.wcet.seconds if codel.wcet else None)
    return out


def _offset(text: str, line: int, column: int) -> int:
    """The index in ``text`` of a 1-based line and column."""
    starts = [0] + [m.end() for m in re.finditer(r"\n", text)]
    return starts[line - 1] + column - 1


def _declaration_end(text: str, start: int) -> int:
    """The index of the ``;`` that ends the declaration starting at ``start`` (comments skipped), -1 if none."""
    i = start
    while i < len(text):
        if text.startswith("/*", i):
            close = text.find("*/", i + 2)
            i = len(text) if close < 0 else close + 2
        elif text.startswith("//", i):
            close = text.find("\n", i)
            i = len(text) if close < 0 else close + 1
        elif text[i] == ";":
            return i
        else:
            i += 1
    return -1


def _set_one(text: str, place: Place, ms: float, name: str) -> str:
    """``text`` with the declaration at ``place`` declaring ``wcet ms``."""
    start = _offset(text, place.span.line, place.span.column)
    end = _declaration_end(text, start)
    if not text.startswith(name.rsplit(".", 1)[1], start) or end < 0:
        raise WcetEditError(f"{place.span}: cannot find the declaration of codel {name} (a codel name, then ';')")
    head = text[start:end]
    if place.seconds is not None:
        found = list(_WCET.finditer(head))
        if not found:
            raise WcetEditError(f"{place.span}: codel {name} declares a wcet that is not in its declaration "
                                "(a macro?); set it by hand")
        head = head[:found[-1].start()].rstrip()
    else:
        head = head.rstrip()
    return text[:start] + f"{head} wcet {ms:g} ms" + text[end:]


def edited_texts(paths: Sequence[str | Path], wanted: Mapping[str, float]) -> dict[Path, str]:
    """The new text of each description file in which ``wanted`` (ms by ``Module.Owner.codel``) changes a wcet."""
    places = codels(read_description(paths))
    unknown = [name for name in wanted if name not in places]
    if unknown:
        raise WcetEditError(f"no such codel in {', '.join(str(p) for p in paths)}: {', '.join(unknown)}")
    bad = [f"{name} = {ms!r}" for name, ms in wanted.items() if not 0 < ms < float("inf")]
    if bad:
        raise WcetEditError(f"a WCET is a positive number of ms: {', '.join(bad)}")
    texts: dict[Path, str] = {}
    # from the end of each file backwards, so that an edit never moves the place of one still to come
    for name in sorted(wanted, key=lambda n: (places[n].span.file, -places[n].span.line, -places[n].span.column)):
        file = Path(places[name].span.file)
        if file not in texts:
            texts[file] = file.read_text(encoding="utf-8")
        texts[file] = _set_one(texts[file], places[name], wanted[name], name)
    return {file: text for file, text in texts.items() if text != file.read_text(encoding="utf-8")}


def _read_back(paths: Sequence[str | Path], texts: Mapping[Path, str], wanted: Mapping[str, float]) -> None:
    """Parse the new texts in a copy of the descriptions' folders; each codel must declare the WCET asked."""
    folders = sorted({Path(p).resolve() if Path(p).is_dir() else Path(p).resolve().parent for p in paths})
    with tempfile.TemporaryDirectory(prefix="wcets-") as tmp:
        copies = {folder: Path(tmp) / str(i) for i, folder in enumerate(folders)}
        for folder, copy in copies.items():
            shutil.copytree(folder, copy, ignore=shutil.ignore_patterns("__pycache__"))

        def moved(path: Path) -> Path:
            real = Path(path).resolve()
            folder = next(f for f in folders if real.is_relative_to(f))
            return copies[folder] / real.relative_to(folder)

        for file, text in texts.items():
            moved(file).write_text(text, encoding="utf-8")
        got = codels(read_description([moved(Path(p)) for p in paths]))
    wrong = [name for name, ms in wanted.items() if got[name].seconds is None
             or abs(got[name].seconds * 1e3 - ms) > 1e-9 * max(1.0, ms)]
    if wrong:
        raise AssertionError(f"the edited descriptions do not read back the WCET asked for: {', '.join(wrong)}")


def set_wcets(paths: Sequence[str | Path], wanted: Mapping[str, float]) -> list[Path]:
    """Declare ``wanted`` (ms by ``Module.Owner.codel``) in the description files; the files changed.

    Nothing is written unless every codel is found and the edited descriptions parse, check and read back the
    WCETs asked for.
    """
    texts = edited_texts(paths, wanted)
    if texts:
        _read_back(paths, texts, wanted)
    for file, text in texts.items():
        write_file(file, lambda f, text=text: f.write(text))
    return sorted(texts)
