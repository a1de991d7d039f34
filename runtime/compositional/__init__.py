"""Compositional deadlock analysis (D-Finder style) of flat BIP systems: invariants, DIS, SAT, verdicts.

Verification only: it reads the flat system the engine and the explorer read
(runtime/engine/flatten.py), and calls the explorer only to decide the
candidates it cannot refute.  The generated controller never imports it.
docs/verification/compositional.md explains the method and what each verdict means.
"""
from runtime.compositional.analysis import Analysis, Potential, analyse, dependency_graph, wait_cycles
from runtime.compositional.check import decide
from runtime.compositional.traps import TrapStore

__all__ = ["Analysis", "Potential", "TrapStore", "analyse", "decide", "dependency_graph", "wait_cycles"]
