"""Helpers shared by the verification tests: fixture models, state spaces, the NDD module built once."""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path

from runtime.bip2 import parse_file, parse_text
from runtime.explore import StateSpace

ROOT = Path(__file__).resolve().parents[1]
FIXTURES = ROOT / "tests" / "fixtures" / "verify"
NDD = ROOT / "descriptions" / "dala" / "NDD.gen"
NDD_NO_AFTER = FIXTURES / "ndd_no_after" / "NDD.gen"


@lru_cache(maxsize=None)
def package(name: str):
    return parse_file(str(FIXTURES / f"{name}.bip"))


def space(name: str, root: str, **kw) -> StateSpace:
    return StateSpace(package(name), root, **kw)


def text_space(text: str, root: str = "Main()", **kw) -> StateSpace:
    return StateSpace(parse_text(text, "Inline.bip"), root, **kw)


@lru_cache(maxsize=None)
def ndd_model(path: str = str(NDD)):
    """(package, root) of a single NDD description built as the generator builds it (its own constraints only)."""
    from genom2bip.generate import model_of
    from genom2bip.parser import parse_paths

    package, root, _ = model_of(parse_paths([path]), "NDD")
    return package, root
