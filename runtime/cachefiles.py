"""Where compiled artefacts are cached (compiled C libraries, code objects of large generated sources, the grammars'
parser tables), and how a file there is written so that concurrent writers never see half of it."""
from __future__ import annotations

import os
import tempfile
from pathlib import Path


def cache_dir() -> Path:
    """``$GENOM2BIP_CACHE``, else ``$XDG_CACHE_HOME/genom2bip/native`` (``~/.cache`` without it)."""
    base = os.environ.get("GENOM2BIP_CACHE")
    if base:
        return Path(base)
    xdg = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(xdg) / "genom2bip" / "native"


def write_atomic(path: Path, data: bytes) -> None:
    """Write atomically: concurrent builds of the same model never see half a file.

    Each writer has a temporary file of its own (not one per process: two threads of a campaign's worker, or
    two hosts sharing the cache, may build the same library at once); the rename is atomic, the last one wins.
    """
    fd, partial = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.chmod(partial, 0o644)
        os.replace(partial, path)
    except BaseException:
        Path(partial).unlink(missing_ok=True)
        raise
