"""The verification API: build a model from plain parameters, run one check, get a result object.

``genom2bip verify`` is a printer of these results; a campaign records them
as JSON (``result.to_json()``).  This package never imports
``genom2bip.cli``.  Each check returns a :class:`CheckResult` (verdict,
figures, trace, notes)::

    from genom2bip.verify import SearchOptions, build_model, check_deadlock, state_space

    model = build_model(["descriptions/dala/NDD.gen"])  # rules=, defines=, include_dirs=, time=TimeSettings()
    options = SearchOptions(max_states=1_000_000)
    result = check_deadlock(state_space(model, options), options)
    print(result.verdict.value, result.figures.states, result.to_json())

The checks: :func:`check_deadlock` (our explorer), :func:`check_deadlock_compositional`
(invariants and SAT), :func:`spin_deadlock`; :func:`check_property`,
:func:`check_property_localized`, :func:`spin_property`; :func:`check_observer`,
:func:`check_observers`, :func:`check_observer_localized` (timing observers of a
model built with ``time=TimeSettings()``).  A :class:`Listener` hears progress
and notes as they come; the default hears nothing.
"""
from __future__ import annotations

from genom2bip.loading import InputError, TimeSettings, UsageError
from genom2bip.verify.compositional import check_deadlock_compositional
from genom2bip.verify.localized import check_observer_localized, check_property_localized, refuse_unlocalizable
from genom2bip.verify.model import Model, build_model, open_bip, tick_us
from genom2bip.verify.options import Listener, SearchOptions
from genom2bip.verify.properties import read_properties
from genom2bip.verify.results import (
    Candidate, CheckResult, CompositionalResult, Deadlock, DeadlockResult, Figures, ModelError, ObserverResult,
    PropertyResult, Refuted, Trace, Verdict,
)
from genom2bip.verify.search import Exploration, check_deadlock, check_property, explore, state_space
from genom2bip.verify.spin import refuse_for_spin, spin_deadlock, spin_property
from genom2bip.verify.timing import ObserverAtom, check_observer, check_observers, observers

__all__ = [
    "Candidate", "CheckResult", "CompositionalResult", "Deadlock", "DeadlockResult", "Exploration", "Figures",
    "InputError", "Listener", "Model", "ModelError", "ObserverAtom", "ObserverResult", "PropertyResult", "Refuted",
    "SearchOptions", "TimeSettings", "Trace", "UsageError", "Verdict", "build_model", "check_deadlock",
    "check_deadlock_compositional", "check_observer", "check_observer_localized", "check_observers",
    "check_property", "check_property_localized", "explore", "observers", "open_bip", "read_properties",
    "refuse_for_spin", "refuse_unlocalizable", "spin_deadlock", "spin_property", "state_space", "tick_us",
]
