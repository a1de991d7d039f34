"""The compiled search's visited sets (exact, hash compaction, bitstate) and how lossy a finished search was.

``exact`` keeps every packed state.  ``compact`` keeps a 64-bit fingerprint
per state (SPIN's hash compaction, -DHC): a new state whose fingerprint
equals a visited one's is missed.  ``bitstate`` sets 3 bits per state in a
fixed array of 2^bits bits (SPIN's -DBITSTATE, -k3): a new state whose 3
bits are all set already is missed.  :func:`lossiness` words the
probability of such an omission after a search, as SPIN states its hash
factor.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

#: The store's code in search.c (ST_EXACT, ST_COMPACT, ST_BITSTATE).
STORES = {"exact": 0, "compact": 1, "bitstate": 2}
#: Bits of the bitstate array by default: 2^32 bits, 512 MB.
DEFAULT_BITS = 32
FINGERPRINT_BITS = 64


@dataclass
class Lossiness:
    """How likely a lossy search missed states: the probability of one omission, and SPIN's hash factor."""

    store: str
    states: int
    table_bits: int  # bitstate: bits of the array; compact: bits of a fingerprint
    probability: float  # that at least one state was missed (an upper bound)
    expected_missed: float
    hash_factor: float | None = None  # bitstate: bits per state

    def line(self) -> str:
        if self.store == "compact":
            return (f"hash compaction: {self.states:,} states stored as {self.table_bits}-bit fingerprints; "
                    f"probability that a state was missed <= {self.probability:.2g} (n^2/2^{self.table_bits + 1})")
        return (f"bitstate: {self.states:,} states in 2^{int(math.log2(self.table_bits))} bits, 3 bits per state; "
                f"hash factor {self.hash_factor:,.1f} (SPIN: best if > 100); expected states missed <= "
                f"{self.expected_missed:.3g}, probability of a miss <= {self.probability:.2g}")


def _bitstate_expected(states: int, bits: int, k: int = 3) -> float:
    """Sum over the stored states of the chance that the i-th was taken as visited: (1 - e^(-k i / m))^k."""
    if states <= 0:
        return 0.0
    steps = min(states, 4096)
    total = 0.0
    for j in range(steps):  # midpoint rule over i in [0, states)
        i = (j + 0.5) * states / steps
        total += (1.0 - math.exp(-k * i / bits)) ** k
    return total * states / steps


def lossiness(store: str, states: int, table_size: int) -> Lossiness | None:
    """None for the exact store; else the omission figures of a search that stored ``states`` states."""
    if store == "exact":
        return None
    if store == "compact":
        p = min(1.0, states * (states - 1) / 2 / 2.0 ** FINGERPRINT_BITS)
        return Lossiness(store, states, FINGERPRINT_BITS, p, p)
    expected = _bitstate_expected(states, table_size)
    return Lossiness(store, states, table_size, min(1.0, expected), expected,
                     table_size / states if states else float("inf"))
