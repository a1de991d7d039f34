"""Each component's C codels loaded, in the controller's process or each library in a process of its own."""
from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Callable

from runtime.ccodels.isolated import IsolatedLibrary
from runtime.ccodels.library import CodelLibrary, CodelLibraryError

#: Set to 1: each component's C codels run in a process of their own (runtime.ccodels.isolated).
PROCESS_ENV = "GENOM2BIP_CODELS_PROCESS"


def c_codels(interface: dict[str, Any], isolate: bool | None = None, clock: Any = None,
             devices: dict[str, Callable[[], Any]] | None = None
             ) -> tuple[dict[str, dict[str, Callable]], dict[str, str], list[str]]:
    """The C codels of every component the interface gives a library: (functions by component, problems by
    component, the libraries loaded).  Libraries are found relative to the package (``interface["where"]``);
    ``isolate`` (default: the environment variable ``GENOM2BIP_CODELS_PROCESS=1``) runs each library in a
    process of its own, so that a codel that crashes fails its request and the controller goes on.  On a
    virtual ``clock`` the codels' wall clock follows it (in the controller's process); ``devices`` are what
    ``genom2bip_device(name)`` gives the codels (in the controller's process; in a process of their own, none)."""
    if isolate is None:
        isolate = os.environ.get(PROCESS_ENV, "") == "1"
    base = Path(interface.get("where") or ".")
    found: dict[str, dict[str, Callable]] = {}
    problems: dict[str, str] = {}
    loaded: list[str] = []
    for component, spec in interface["components"].items():
        c = spec.get("c")
        if not c:
            continue
        try:
            if isolate:
                library: Any = IsolatedLibrary(component, str(base / c["library"]), c)
            else:
                library = CodelLibrary(component, base / c["library"], c)
                if clock is not None and getattr(clock, "virtual", False):
                    library.follow(clock)
                if devices:
                    library.offer(devices)
        except CodelLibraryError as err:
            problems[component] = str(err)
            continue
        loaded.append(library.path)
        found[component] = {name: fn for name in library.codels if (fn := library.get(name)) is not None}
    return found, problems, loaded
