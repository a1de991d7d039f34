"""Turn DOT text into the file a user asked for: ``.dot`` as is, ``.svg`` and ``.png`` through a layout engine.

The layout engine is Graphviz's ``dot`` when the machine has it, else the
``graphviz-pure`` command that the ``graphviz-pure`` package installs with
genom2bip (docs/dependencies.md says why): pictures render on a fresh machine
set up with the README's commands, without a Debian package.
"""
from __future__ import annotations

import os
import shutil
import subprocess
import sysconfig
import tempfile
from pathlib import Path

from runtime.errors import Genom2bipError

FORMATS = (".dot", ".gv", ".svg", ".png")


class PictureError(Genom2bipError):
    """A picture that cannot be written: unknown format, no layout engine, or the engine failed."""


def script_dirs() -> list[str]:
    """Where pip puts the commands of this Python's packages, which PATH may not name (an environment used
    without being activated, ``~/.local/bin`` on a fresh Debian)."""
    found = [sysconfig.get_path("scripts")]
    if f"{os.name}_user" in sysconfig.get_scheme_names():
        found.append(sysconfig.get_path("scripts", f"{os.name}_user"))
    return found


def layout_command() -> list[str] | None:
    """The command that lays out DOT text: ``dot``, else ``graphviz-pure``; None when neither is installed."""
    for name in ("dot", "graphviz-pure"):
        found = shutil.which(name)
        if found:
            return [found]
    found = shutil.which("graphviz-pure", path=os.pathsep.join(script_dirs()))  # installed with genom2bip
    return [found] if found else None


def layout(text: str, fmt: str, *, fixed_positions: bool = False, what: str = "the picture") -> bytes:
    """DOT ``text`` laid out and rendered as ``fmt`` (``svg``, ``png``) by :func:`layout_command`'s engine.

    ``what`` names the picture in errors (the file being written, the page asking).
    """
    command = layout_command()
    if command is None:
        raise PictureError(f"{what}: no Graphviz layout engine found: `pip install graphviz-pure` "
                           "(installed with genom2bip) or the Debian package graphviz; "
                           "a .dot file needs neither")
    command += ["-Kneato", "-n2"] if fixed_positions else []
    try:
        done = subprocess.run([*command, f"-T{fmt}"], input=text.encode("utf-8"), capture_output=True, timeout=120)
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise PictureError(f"{what}: the layout engine {command[0]} failed: {exc}") from None
    if done.returncode != 0 or not done.stdout:
        detail = done.stderr.decode("utf-8", "replace").strip().splitlines()
        raise PictureError(f"{what}: the layout engine {Path(command[0]).name} failed"
                           + (f": {detail[-1]}" if detail else f" (exit {done.returncode})"))
    return done.stdout


def render(text: str, path: str | Path, *, fixed_positions: bool = False) -> Path:
    """Write ``text`` (DOT) to ``path`` in the format its suffix names; atomic: a failure leaves no file.

    ``fixed_positions`` keeps the ``pos`` of every node (``neato -n2``), for
    pictures laid out by us, such as sequence diagrams.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in FORMATS:
        raise PictureError(f"{path}: unknown picture format {suffix or '(none)'!r}; use one of {', '.join(FORMATS)}")
    if suffix in (".dot", ".gv"):
        data = text.encode("utf-8")
    else:
        data = layout(text, suffix[1:], fixed_positions=fixed_positions, what=str(path))
    _write_atomically(path, data)
    return path


def _write_atomically(path: Path, data: bytes) -> None:
    """Write beside the target, then rename: a reader never sees half a picture."""
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent if str(path.parent) else ".")
    except OSError as exc:
        raise PictureError(f"cannot write {path}: {exc.strerror or exc}") from None
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    except OSError as exc:
        Path(tmp).unlink(missing_ok=True)
        raise PictureError(f"cannot write {path}: {exc.strerror or exc}") from None


def _umask() -> int:
    """The process's umask (mkstemp creates files 0600; a picture is as readable as any file the user writes)."""
    mask = os.umask(0)
    os.umask(mask)
    return mask
