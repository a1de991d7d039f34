"""The timed BIP2 rules of the builder: clocks, ``resume``, atom invariants and clock rates ``x' = e``."""
from __future__ import annotations

from lark import Token

from runtime.model import ClockDecl, Invariant, Rate, Resume


class TimedBuilder:
    """Mixed into :class:`runtime.bip2.builder.Builder`; relies on its ``span`` and ``locator``."""

    def clock_decl(self, children):
        _annotations, *names = children
        unit = names.pop() if isinstance(names[-1], Token) and names[-1].type == "TIME_UNIT" else None
        names = [n for n in names if n is not None]
        return [ClockDecl(tok.value, unit.value if unit else None, span=self.span(tok)) for tok in names]

    def resume(self, children):
        keyword, guard = children
        return Resume(guard, span=self.span(keyword))

    def atom_invariant(self, children):
        _keyword, name, places, guard = children
        inv = Invariant(name.value, [], guard, span=self.span(name))
        if places is not None:
            inv.exact, tokens = places
            inv.places = self._note_names(inv, "places", tokens)
        return inv

    def invariant_at(self, children):
        return True, children[0].tokens

    def invariant_from(self, children):
        return False, children[0].tokens

    def rate_assign(self, children):
        clock, _quote, value = children
        stmt = Rate(clock.value, value)
        self.locator.note(stmt, self.span(clock))
        return stmt
