"""Interaction numbers of the compiled search: dense per source, 32 bits per parent link when they fit, else 64.

The search stores, with each state, the number of the interaction that
first reached it.  Source ``k``'s interactions are numbered from its offset:
a rendezvous or a lone port has one interaction (the offset itself, its mask
is never computed, so a rendezvous may have any number of ports), a
connector with triggers or sub-connectors one per mask (offset + mask, masks
of at most ``cstep.MAX_PARAMS`` bits).  When every number fits in 32 bits
(``UINT32_MAX`` means none) the links stay 4 bytes per state; past that they
take 8 (``VIA_BITS`` 64 in the C text).  The Python side turns a number back
into the source and mask, and from them into the engine's own interaction.
"""
from __future__ import annotations

from bisect import bisect_right
from dataclasses import dataclass

#: Source kinds with a single interaction: numbered by their offset alone.
SINGLE = ("rendezvous", "port")
#: Numbers up to this one (excluded: it means "no interaction") fit the 32-bit layout.
NONE32 = (1 << 32) - 1
#: Numbers must stay below this one in the 64-bit layout (C reads them back as signed 64-bit ints).
LIMIT64 = (1 << 63) - 1


class TooMany(Exception):
    """More interactions than 64-bit numbers hold (the caller refuses the model by name)."""


@dataclass(frozen=True)
class Numbering:
    """The offset of each source, whether it has one interaction, and the width of a stored number."""

    offsets: tuple[int, ...]
    single: tuple[bool, ...]
    fulls: tuple[int, ...]  # the mask of every port of the source (what a single interaction's mask is)
    total: int  # numbers in use: 0 .. total - 1
    bits: int  # 32 or 64

    @classmethod
    def of(cls, sources, wide: bool = False) -> Numbering:
        """The numbering of ``sources`` (runtime.engine.plan's); ``wide`` takes 64 bits even when 32 fit."""
        offsets, single, total = [], [], 0
        for src in sources:
            offsets.append(total)
            one = src.kind in SINGLE
            single.append(one)
            total += 1 if one else src.full + 1
        if total >= LIMIT64:
            raise TooMany(f"{len(offsets)} sources with {total:,} interactions: more than 64-bit numbers hold")
        bits = 64 if wide or total >= NONE32 else 32
        return cls(tuple(offsets), tuple(single), tuple(s.full for s in sources), total, bits)

    def number(self, src: int, mask: int) -> int:
        """The number of interaction ``mask`` of source ``src``."""
        return self.offsets[src] if self.single[src] else self.offsets[src] + mask

    def interaction(self, number: int) -> tuple[int, int]:
        """``(source, mask)`` of a number (ValueError for one that names no interaction)."""
        if not 0 <= number < self.total:
            raise ValueError(f"interaction number {number} out of 0..{self.total - 1}")
        src = bisect_right(self.offsets, number) - 1
        if self.single[src]:
            return src, self.fulls[src]
        mask = number - self.offsets[src]
        if mask == 0:
            raise ValueError(f"interaction number {number} is the empty interaction of source {src}")
        return src, mask

    def c_define(self) -> str:
        """The layout of the numbers the search stores (before prelude.h, which types ``VIA_T`` by it)."""
        return f"#define VIA_BITS {self.bits}"

    def c_offsets(self) -> str:
        """``OFF``: the first number of each source (an interaction's number is ``OFF[src] + mask`` or ``OFF[src]``)."""
        suffix = "u" if self.bits == 32 else "ull"
        values = ", ".join(f"{o}{suffix}" for o in self.offsets) or "0"
        return f"static const VIA_T OFF[NSRC > 0 ? NSRC : 1] = {{{values}}};"
