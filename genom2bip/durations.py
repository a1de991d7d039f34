"""Durations as the files people write say them: ``10 ms``, ``1.5 s``, ``500 us``."""
from __future__ import annotations

import re

from genom2bip.parser.limits import MAX_DURATION

UNITS = {"s": 1_000_000, "ms": 1000, "us": 1, "µs": 1, "min": 60_000_000}
DURATION = re.compile(r"\s*(\d+(?:\.\d+)?)\s*(s|ms|us|µs|min)\s*\Z")


def parse_duration(text: str) -> int | None:
    """``1 s``, ``250 ms``, ``10 us`` → microseconds; None when it is not a duration of at most a day."""
    m = DURATION.match(text)
    if not m or len(m.group(1)) > 20:  # float() of thousands of digits is infinite
        return None
    value = float(m.group(1)) * UNITS[m.group(2)]
    return round(value) if value <= MAX_DURATION * 1e6 else None
