"""Builder corner cases: names that meet in one module."""
from genom2bip.build import build_package
from genom2bip.parser import parse_text
from runtime.engine import flatten


def test_a_task_named_like_a_service_gets_labels_of_its_own():
    description = parse_text("""
component clash {
  task motion { period 10 ms; codel <start> t0() yield pause::start; };
  activity motion() { task motion; codel <start> m0() yield ether; };
};
""", "clash.gen")
    flat = flatten(build_package(description, "clash"), "CLASH()")
    labels = [c.label for c in flat.connectors if c.top]
    assert len(labels) == len(set(labels)), sorted(labels)
    assert {"clash.motion_task:exec_start", "clash.motion:exec_start", "clash.motion_task:period"} <= set(labels)
    assert "clash.motion_task.scheduler" in [a.name for a in flat.atoms]
