"""State-space exploration of BIP models on the engine's own compiled step (docs/verification/explorer.md).

``StateSpace`` numbers packed states lazily (codel outcomes and the
environment's requests are its choice points); ``explore`` walks it
breadth-first or depth-first and reports deadlocks and model errors.
"""
from runtime.explore.choices import Choice, ExploreError
from runtime.explore.codec import DomainError
from runtime.explore.progress import Progress
from runtime.explore.search import ExploreResult, Finding, explore
from runtime.explore.space import LimitReached, StateSpace, Step

__all__ = ["Choice", "DomainError", "ExploreError", "ExploreResult", "Finding", "LimitReached", "Progress",
           "StateSpace", "Step", "explore"]
