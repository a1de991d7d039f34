"""Helpers for tests of the run-time controller: a model and its interface from a description text, DALA's."""
from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DALA_CODELS = ROOT / "tests" / "fixtures" / "dala_codels"


def build(tmp_path: Path, text: str, name: str = "tick"):
    """(package, root, interface) of a GenoM3 description given as text, through the generator's back ends."""
    from genom2bip.back.interface import interface_data
    from genom2bip.generate import model_of
    from genom2bip.parser import parse_paths

    path = tmp_path / f"{name}.gen"
    path.write_text(text)
    description = parse_paths([path])
    package, root, _ = model_of(description, name)
    return package, root, interface_data(description, name, str(path))


def dala():
    """The committed generated DALA package (gen/dala)."""
    if str(ROOT / "gen") not in sys.path:
        sys.path.insert(0, str(ROOT / "gen"))
    import dala as package

    return package


#: A component with a 10 ms task on a 4 ms clock, a slow activity and a function run by the control task.
TICK = """
component tick {
  clock-rate 4 ms;
  exception e_slow;
  ids { long n; double seconds; };
  port out long Count;

  task t {
    period 10 ms;
    codel <start> tickStart(ids out n) yield count;
    codel <count> tickCount(ids inout n, port out Count) yield pause::count;
  };

  activity Slow(in double seconds = 0.05 : "how long the codel takes") {
    task t;
    codel <start> tickSlow(local in seconds) yield ether;
    throw e_slow;
  };

  function Work(in long add = 1, out long total) {
    codel <start> tickWork(local in add, ids inout n, local out total) yield ether;
  };
};
"""
