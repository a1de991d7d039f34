"""The BIP engine: flatten a package, generate and compile its step once, run or explore it.

``Engine(package, root="System()", externs=None)`` gives ``initial_state()``,
``enabled(state)``, ``fire(state, interaction)`` and ``run(policy, limit, tracer)``.
"""
from runtime.engine.engine import Engine, RunSummary
from runtime.engine.errors import EngineError, ExternError, FlattenError, ModelError
from runtime.engine.externs import bind_externs
from runtime.engine.flatten import FlatSystem, flatten
from runtime.engine.interaction import Interaction, interaction_label
from runtime.engine.policies import InteractivePolicy, RandomPolicy, first, make_policy
from runtime.engine.trace import ConsoleTracer, JsonlTracer, MemoryTracer, MultiTracer, StepRecord, Tracer

__all__ = [
    "ConsoleTracer", "Engine", "EngineError", "ExternError", "FlatSystem", "FlattenError", "Interaction",
    "InteractivePolicy", "JsonlTracer", "MemoryTracer", "ModelError", "MultiTracer", "RandomPolicy", "RunSummary",
    "StepRecord", "Tracer", "bind_externs", "first", "flatten", "interaction_label", "make_policy",
]
