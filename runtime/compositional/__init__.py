"""Compositional deadlock analysis (D-Finder style) of flat BIP systems: invariants, DIS, SAT, verdicts.

Verification only: it reads the flat system the engine and the explorer read
(runtime/engine/flatten.py), and calls the explorer only to decide the
candidates it cannot refute.  The generated controller never imports it.
docs/verification/compositional.md explains the method and what each verdict means.
"""
import importlib

#: Each name the package exports, and the module it comes from: loaded on first use (PEP 562), so that importing a
#: light module of the package (solver.py) does not load networkx and python-sat.
_EXPORTS = {"Analysis": "analysis", "Potential": "analysis", "analyse": "analysis", "dependency_graph": "analysis",
            "wait_cycles": "analysis", "decide": "check", "TrapStore": "traps"}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name not in _EXPORTS:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{_EXPORTS[name]}"), name)
