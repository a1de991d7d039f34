"""Properties and timing observers of a model too large to explore, by localization with counterexample-guided
refinement (``runtime.localize``): the atoms a property involves kept exact, the others a free environment.

Deadlock freedom is not preserved by localization; it stays with the
compositional analysis (:mod:`genom2bip.verify.compositional`).
"""
from __future__ import annotations

from genom2bip.loading import InputError
from genom2bip.verify.model import Model
from genom2bip.verify.options import Listener, SearchOptions
from genom2bip.verify.results import ObserverResult, PropertyResult
from genom2bip.verify.search import extern_bindings, limit_of, property_result
from genom2bip.verify.timing import ObserverAtom, check_observer

#: States one round's search may visit unless ``max_states`` says otherwise: the rounds that prove DALA's properties
#: and observers take at most about five million (goto_needs_map); past this, refinement has kept too much to stay
#: cheap.
ROUND_STATES = 10_000_000


def refuse_unlocalizable(items) -> None:
    """Raise :class:`~genom2bip.loading.InputError` naming (file:line:column) each property localization cannot take.

    Deadlock freedom passes: the compositional analysis answers it.
    """
    from runtime.localize.refine import localizable

    refused = []
    for item in items:
        why = "" if item.property.pattern == "deadlock free" else localizable(item)
        if why:
            refused.append(f"{item.property.span}: property {item.name}: not checked by --method compositional: "
                           f"{why}")
    if refused:
        raise InputError([*refused, "check these with --method explore on a model the search can finish "
                                    "(e.g. one module)"])


def check_property_localized(model: Model, item, options: SearchOptions | None = None,
                             listener: Listener | None = None) -> PropertyResult:
    """A safety property or a possibility, by rounds of abstraction and refinement (NotLocalizable for another)."""
    from runtime.localize.refine import check_localized

    options = options or SearchOptions()
    listener = listener or Listener()
    rounds = []

    def on_round(r) -> None:
        rounds.append(r)
        listener.round(len(rounds), r)

    found = check_localized(model.package, model.root, item, extern_bindings(options.externs),
                            max_states=_round_states(options), max_bytes=options.max_bytes, on_round=on_round)
    limit = limit_of(found.verdict)  # before the note is reworded
    result = property_result(item, _capped(found.verdict, options))
    result.limit = result.limit or limit
    return result


def check_observer_localized(model: Model, atom: ObserverAtom, options: SearchOptions | None = None,
                             listener: Listener | None = None) -> ObserverResult:
    """Is ``atom``'s ERROR place reachable?  By localization: the observer, what forces its close event in time and
    what the rounds add kept exact."""
    return check_observer(model, atom, decide=lambda item: check_property_localized(model, item, options, listener))


def _round_states(options: SearchOptions) -> int:
    return options.max_states if options.max_states is not None else ROUND_STATES


def _capped(verdict, options: SearchOptions):
    """An inconclusive verdict says that the rounds' default limit stopped it, and how to lift it."""
    if verdict.holds is None and options.max_states is None and "max-states" in (verdict.note or ""):
        verdict.note = (f"a round stopped at {ROUND_STATES:,} states (the default limit of a localization round; "
                        "--max-states N sets another)")
    return verdict
