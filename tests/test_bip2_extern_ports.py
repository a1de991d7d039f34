"""``extern port T p(x) as "Name" policy``: read, checked, written back (running them: test_engine_extern_ports)."""
from __future__ import annotations

from pathlib import Path

import pytest

from genom2bip.back.bip2 import write_package
from runtime.bip2 import parse_file, parse_text
from runtime.diagnostics import DiagnosticError

FIXTURE = Path(__file__).parent / "fixtures" / "bip" / "roundtrip" / "rt_extern_ports.bip"


def test_extern_ports_are_read_with_their_backend_and_policy():
    ports = {p.name: (p.extern, p.exported, p.type, p.data, p.backend, p.policy)
             for p in parse_file(FIXTURE).atom_types[0].ports}
    assert ports == {
        "p": (False, True, "Port", [], None, None),
        "sample": (True, False, "IntPort", ["last"], "Sampler", "remember"),
        "tick": (True, False, "IntPort", ["count"], "Clock", "ignore"),
        "fault": (True, False, "IntPort", ["count"], None, "error"),
        "wake": (True, False, "Port", [], None, None),
    }


def test_several_extern_ports_in_one_declaration_share_backend_and_policy():
    text = FIXTURE.read_text().replace('    extern port Port wake()\n',
                                       '    extern port Port wake(), rest() as "Bell" ignore\n')
    text = text.replace(
        "    on wake from WAIT to DONE\n", "    on wake from WAIT to DONE\n    on rest from DONE to WAIT\n"
    )
    model = parse_text(text, "rt_extern_ports.bip")
    ports = {p.name: (p.backend, p.policy) for p in model.atom_types[0].ports if p.extern}
    assert ports["wake"] == ports["rest"] == ("Bell", "ignore")
    written = write_package(model)
    assert 'extern port Port wake() as "Bell" ignore\n' in written
    assert 'extern port Port rest() as "Bell" ignore\n' in written
    assert parse_text(written, "rt_extern_ports.bip") == model


def test_written_back_as_declared():
    written = write_package(parse_file(FIXTURE))
    assert '    extern port IntPort sample(last) as "Sampler" remember\n' in written
    assert '    extern port IntPort fault(count) error\n' in written
    assert '    extern port Port wake()\n' in written


@pytest.mark.parametrize("old, new, message, column", [
    ('as "Sampler" remember', 'as "Sampler" forget', "expected", 51),
    ("extern port IntPort tick(count)", "extern port IntPort tick(counts)", "unknown variable 'counts' bound to port "
     "'tick'", 30),
    ("extern port Port wake()", "extern port Pot wake()", "unknown port type 'Pot'", 17),
])
def test_bad_declarations_are_located(old, new, message, column):
    text = FIXTURE.read_text().replace(old, new)
    line = text[:text.index(new)].count("\n") + 1
    with pytest.raises(DiagnosticError) as err:
        parse_text(text, "rt_extern_ports.bip")
    rendered = err.value.render()
    assert f"rt_extern_ports.bip:{line}:{column}: error: " in rendered and message in rendered, rendered


def test_a_connector_cannot_bind_an_extern_port():
    text = FIXTURE.read_text().replace(
        "  compound type System()\n    component Sensor s(1)\n",
        "  connector type One(IntPort q)\n    define q\n  end\n\n"
        "  compound type System()\n    component Sensor s(1)\n    connector One c(s.sample)\n")
    with pytest.raises(DiagnosticError) as err:
        parse_text(text, "rt_extern_ports.bip")
    assert ("port 'sample' of component 's' (atom type Sensor) is an extern port: events from outside the model "
            "fire it, no connector") in err.value.render()
