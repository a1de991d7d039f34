"""The C step on what it took last: nested connectors, timed models, floats, strings, wide connectors; refusals."""
from __future__ import annotations

from pathlib import Path

import pytest

from genom2bip.build.timed import TimeOptions
from genom2bip.generate import model_of
from genom2bip.parser import parse_paths
from genom2bip.rules import description_rules
from runtime.explore import StateSpace
from runtime.native import compiled as native
from tests import enginekit, verifykit
from tests.nativekit import agree, compiled, needs_cc
from tests.test_native import same_search

pytestmark = needs_cc
ROOT = Path(__file__).resolve().parents[1]


def timed(path: str, name: str, **options):
    description = parse_paths([ROOT / path])
    package, root, _ = model_of(description, name, description_rules(description), TimeOptions(**options))
    return package, root


@pytest.mark.parametrize("package, root", [(enginekit.package("Hierarchy"), "Module()"),
                                           (enginekit.package("Hierarchy"), "System()"),
                                           (enginekit.package("NestedAny"), "System()"),
                                           (verifykit.package("Mix"), "Main()")])
def test_nested_connectors_have_the_same_successors(package, root):
    space = StateSpace(package, root)
    assert agree(space, compiled(space)) == len(space)


def test_nested_connectors_search_as_the_python_explorer():
    same_search((verifykit.package("Mix"), "Main()"))


@pytest.mark.parametrize("wcet", [0, 10_000, 40_000])
def test_timed_cruise_agrees_state_by_state_and_in_the_search(wcet):
    package, root = timed("tests/fixtures/timed/Cruise.gen", "Cruise", default_wcet_us=wcet)
    space = StateSpace(package, root)
    assert agree(space, compiled(space)) == len(space)
    same_search((package, root))


def test_timed_ndd_agrees_on_its_first_states_and_counts_as_python():
    package, root = timed("descriptions/dala/NDD.gen", "NDD")
    space = StateSpace(package, root)
    assert agree(space, compiled(space), limit=1500) == 1500
    result = compiled(StateSpace(package, root)).explore()
    assert (result.states, result.transitions, result.depth, result.complete) == (66_560, 473_088, 33, True)
