"""Writing ``<out>/<system>/`` without ever losing a file: only what genom2bip wrote is replaced.

A generated directory holds a marker, ``.genom2bip``, that lists every file
the generator wrote with its SHA-256 (as build tools tag their output
directories).  Writing again replaces those files at once (a staging
directory is renamed into place) and carries over anything else found there
(a user's notes, Python's ``__pycache__``).  It refuses, before writing
anything: a directory without the marker, a listed file changed since it was
written, a symbolic link, a file where a directory should be, and an output
that is or contains one of the inputs.  Nothing is deleted that the
generator did not write.
"""
from __future__ import annotations

import contextlib
import hashlib
import os
import re
import stat
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TextIO, TypeVar

from runtime.errors import Genom2bipError

T = TypeVar("T")

MARKER = ".genom2bip"
_HEADER = ("genom2bip output: `genom2bip ... -o DIR` replaces the files listed below when it runs again\n"
           "and keeps any other file of this directory. Do not edit the listed files.\n")
_ENTRY = re.compile(r"^([0-9a-f]{64})  (\S.*)$")


class OutputError(Genom2bipError):
    """The output directory cannot be written safely; nothing was changed."""


def encode(text: str) -> bytes:
    """UTF-8; a file name that is not UTF-8 (a surrogate escape) is written as ``\\xff`` rather than failing."""
    return text.encode("utf-8", "backslashreplace")


def marker_text(files: dict[str, bytes]) -> str:
    """The marker for a directory holding exactly ``files`` (name → bytes), sorted so that output is deterministic."""
    lines = [f"{_digest(data)}  {name}\n" for name, data in sorted(files.items())]
    return _HEADER + "".join(lines)


def _digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def read_marker(directory: Path) -> dict[str, str] | None:
    """File name → SHA-256 as the marker of ``directory`` lists them; None when it has no readable marker."""
    path = directory / MARKER
    try:
        if not stat.S_ISREG(path.lstat().st_mode):
            return None
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return None
    if not text.startswith(_HEADER):
        return None
    out: dict[str, str] = {}
    for line in text[len(_HEADER):].splitlines():
        m = _ENTRY.match(line)
        if not m or "/" in m.group(2) or m.group(2) in (".", "..", MARKER):
            return None
        out[m.group(2)] = m.group(1)
    return out


def _unchanged(path: Path, digest: str) -> bool:
    """True when ``path`` is a regular file (not a link) whose content has the recorded digest."""
    try:
        if not stat.S_ISREG(path.lstat().st_mode):
            return False
        return _digest(path.read_bytes()) == digest
    except OSError:
        return False


def _is_within(inner: Path, outer: Path) -> bool:
    return inner == outer or outer in inner.parents


def _real(path: Path) -> Path:
    """Where ``path`` leads, links followed as far as they go (a loop of links is no error here: reading says so)."""
    return Path(os.path.realpath(path))


def check_files_are_not_inputs(outputs: list[Path], inputs: list[Path]) -> None:
    """Refuse an output file that is one of the inputs, or a file of an input directory (``--aut NDD.gen``)."""
    files = [f for item in inputs if item.is_dir() for f in sorted(item.iterdir()) if f.is_file()]
    read = {_real(item): item for item in [*inputs, *files]}
    for out in outputs:
        if _real(out) in read:
            raise OutputError(f"refusing to write {out}: it is the input {read[_real(out)]}")


def write_file(path: Path, write: Callable[[TextIO], T]) -> T:
    """Write ``path`` atomically: ``write`` fills a temporary file beside it, renamed over it once complete.

    An error or Ctrl-C in the middle leaves the previous file as it was, never a truncated one.
    """
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8", errors="backslashreplace", newline="\n") as f:
            result = write(f)
        os.chmod(tmp, _mode_for(path))
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    return result


def _mode_for(path: Path) -> int:
    """The permissions of the file being replaced, else what the umask gives a new file."""
    try:
        return stat.S_IMODE(path.stat().st_mode)
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def check_inputs(target: Path, inputs: list[Path]) -> None:
    """Refuse an output directory that is, or contains, one of the inputs."""
    where = _real(target)
    for item in inputs:
        if _is_within(_real(item), where):
            what = "is" if _real(item) == where else "contains"
            raise OutputError(f"refusing to write {target}: it {what} the input {item}; choose another -o DIR")


def kept_entries(target: Path, files: dict[str, str]) -> list[str]:
    """What of an existing ``target`` is not the generator's and is carried over; refuses what must not be replaced."""
    try:
        mode = target.lstat().st_mode
    except FileNotFoundError:
        return []
    if stat.S_ISLNK(mode):
        raise OutputError(f"refusing to write {target}: it is a symbolic link; genom2bip replaces only "
                          f"a directory it wrote itself")
    if not stat.S_ISDIR(mode):
        raise OutputError(f"refusing to write {target}: it exists and is not a directory")
    recorded = read_marker(target)
    if recorded is None:
        raise OutputError(f"refusing to replace {target}/: genom2bip did not write it (no valid {MARKER} marker); "
                          f"move it away or choose another -o DIR")
    changed = sorted(name for name, digest in recorded.items()
                     if os.path.lexists(target / name) and not _unchanged(target / name, digest))
    if changed:
        raise OutputError(f"refusing to replace {target}/: {', '.join(changed)} changed since genom2bip wrote "
                          f"{'them' if len(changed) > 1 else 'it'}; move {'them' if len(changed) > 1 else 'it'} "
                          f"away to regenerate")
    kept = sorted(e.name for e in os.scandir(target) if e.name != MARKER and e.name not in recorded)
    clash = [name for name in kept if name in files]
    if clash:
        raise OutputError(f"refusing to replace {target}/: {', '.join(clash)} would be overwritten, and "
                          f"genom2bip did not write {'them' if len(clash) > 1 else 'it'}")
    return kept


def _own_files(directory: Path) -> dict[str, str] | None:
    """The files of a generated ``directory`` that genom2bip wrote, marker included; None when it has no marker."""
    recorded = read_marker(directory)
    if recorded is None:
        return None
    recorded[MARKER] = _digest((directory / MARKER).read_bytes())
    return recorded


def _remove_own(directory: Path, recorded: dict[str, str]) -> bool:
    """Delete the unchanged files of ``directory`` that ``recorded`` lists, then the directory if it is empty."""
    try:
        for name, digest in recorded.items():
            if _unchanged(directory / name, digest):
                (directory / name).unlink()
        directory.rmdir()
    except OSError:
        return False
    return True


def leftovers(out: Path, name: str) -> list[Path]:
    """Remove what an interrupted run left in ``out`` when it is all the generator's; returns what remains.

    A staging directory (``.NAME.new.*``) with its marker loses the files the
    marker lists, whatever they hold: a run killed while writing one leaves it
    cut short.  A previous output put aside (``.NAME.old.*``) loses only its
    unchanged files.
    """
    remaining = []
    for path in sorted([*out.glob(f".{name}.new.*"), *out.glob(f".{name}.old.*")]):
        if path.is_symlink() or not path.is_dir():
            continue
        recorded = _own_files(path)
        staged = f".{name}.new." in path.name
        if recorded is None or not (_remove_listed(path, list(recorded)) if staged else _remove_own(path, recorded)):
            remaining.append(path)
    return remaining


@dataclass
class Written:
    """What write_tree did: the directory, the entries carried over from the previous one, leftovers it kept."""

    directory: Path
    kept: list[str]
    leftovers: list[Path]


def write_tree(files: dict[str, str | bytes], out: Path, name: str, inputs: list[Path]) -> Written:
    """Write ``files`` as ``<out>/<name>/`` atomically, with the marker; refuses (OutputError) what is unsafe."""
    target = out / name
    data = {file_name: text if isinstance(text, bytes) else encode(text) for file_name, text in files.items()}
    if os.path.lexists(out) and not out.is_dir():
        raise OutputError(f"cannot write {out}: it exists and is not a directory")
    check_inputs(target, inputs)
    kept = kept_entries(target, files)
    made = _missing_parents(out)
    out.mkdir(parents=True, exist_ok=True)
    staging = None
    try:
        remaining = leftovers(out, name)
        staging = Path(tempfile.mkdtemp(prefix=f".{name}.new.", dir=out))
        os.chmod(staging, _directory_mode(target))  # mkdtemp makes it 0700 whatever the umask
        # The marker goes first: a staging directory left by a killed run is then recognised and cleared.
        (staging / MARKER).write_bytes(encode(marker_text(data)))
        for file_name, content in data.items():
            (staging / file_name).write_bytes(content)
        if os.path.lexists(target):
            _swap(staging, target, kept)
        else:
            staging.rename(target)
    except BaseException:
        # A full disk or Ctrl-C: every file of the staging directory is one this run began, finished or not.
        if staging is not None and staging.is_dir():
            _remove_listed(staging, [MARKER, *data])
        for directory in made:  # the directories this run made, when they hold nothing
            with contextlib.suppress(OSError):
                directory.rmdir()
        raise
    return Written(target, kept, remaining)


def _directory_mode(target: Path) -> int:
    """The permissions of the package directory being replaced, else what the umask gives a new directory."""
    try:
        return stat.S_IMODE(os.stat(target).st_mode)
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o777 & ~umask


def _missing_parents(out: Path) -> list[Path]:
    """``out`` and those of its parents that do not exist yet, innermost first."""
    missing = []
    for directory in [out, *out.parents]:
        if os.path.lexists(directory):
            break
        missing.append(directory)
    return missing


def _remove_listed(directory: Path, names: list[str]) -> bool:
    """Delete the files ``names`` of ``directory`` whatever they hold (cut short, say), then the directory if empty."""
    for name in names:
        path = directory / name
        with contextlib.suppress(OSError):
            if not path.is_symlink() and path.is_file():
                path.unlink()
    try:
        directory.rmdir()
    except OSError:
        return False
    return True


def _swap(staging: Path, target: Path, kept: list[str]) -> None:
    """Rename ``staging`` to ``target``, carry ``kept`` entries over from the old one, remove the old one's files."""
    old = Path(tempfile.mkdtemp(prefix=f".{target.name}.old.", dir=target.parent))
    old.rmdir()
    target.rename(old)
    try:
        staging.rename(target)
    except BaseException:
        old.rename(target)
        raise
    for entry in kept:
        try:
            (old / entry).rename(target / entry)
        except OSError:
            pass  # reported below: the old directory is then not empty
    if not _remove_own(old, _own_files(old) or {}):
        raise OutputError(f"wrote {target}/, but could not carry everything over from the previous output: "
                          f"{old}/ keeps what genom2bip did not write; move it back by hand")
