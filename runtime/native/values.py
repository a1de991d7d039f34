"""Explorer states to and from the C step's words: a float slot holds a double's bits, a string slot a number."""
from __future__ import annotations

import struct


def to_words(model, state) -> list[int]:
    """The 64-bit words of an explorer state for the C step (``model``: the generated CModel)."""
    out = [int(v) if not isinstance(v, (float, str)) else 0 for v in state]
    for i in model.floats:
        out[i] = struct.unpack("<q", struct.pack("<d", float(state[i]) + 0.0))[0]
    for i, names in model.strings.items():
        out[i] = names.index(state[i])  # only strings of the model's text reach a state
    return out


def from_words(model, words: list) -> list:
    """An explorer state's values from the C step's words (the inverse of :func:`to_words`)."""
    out = list(words)
    for i in model.floats:
        out[i] = struct.unpack("<d", struct.pack("<q", words[i]))[0]
    for i, names in model.strings.items():
        out[i] = names[words[i]]
    return out
