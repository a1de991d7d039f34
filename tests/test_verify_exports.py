"""verify's exports (--aut, --dot, --promela): never written over an input, never left half-written."""
from pathlib import Path

import pytest

from genom2bip.cli import main

ROOT = Path(__file__).resolve().parents[1]
COUNTER = ROOT / "tests/fixtures/genom3/counter.gen"


@pytest.mark.parametrize("option", ["--aut", "--dot", "--promela"])
def test_an_export_onto_an_input_is_refused(tmp_path, capsys, option):
    source = tmp_path / "counter.gen"
    source.write_bytes(COUNTER.read_bytes())
    prop = tmp_path / "p.mcl"
    prop.write_text('never "counter.GetTicks:fail"\n')
    for target in (source, prop):
        assert main(["verify", str(tmp_path), "--property", str(prop), option, str(target)]) == 1
        assert f"genom2bip: error: refusing to write {target}: it is the input {target}" in capsys.readouterr().err
    assert source.read_bytes() == COUNTER.read_bytes()
    assert prop.read_text() == 'never "counter.GetTicks:fail"\n'


def test_a_failing_export_keeps_the_previous_file_and_leaves_no_temporary(tmp_path, capsys, monkeypatch):
    from runtime.export import lts

    aut = tmp_path / "model.aut"
    aut.write_text("previous LTS\n")

    def broken(space, f):
        f.write("des (0, 1")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(lts, "write_aut", broken)
    assert main(["verify", str(COUNTER), "--aut", str(aut), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert f"genom2bip: error: cannot write {aut}: No space left on device" in err
    assert aut.read_text() == "previous LTS\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["model.aut"]


def test_an_export_replaces_the_file_with_the_same_permissions(tmp_path, capsys):
    pml = tmp_path / "model.pml"
    pml.write_text("old")
    pml.chmod(0o640)
    assert main(["verify", str(COUNTER), "--promela", str(pml), "--quiet"]) == 0
    assert pml.read_text().startswith("/*") or "proctype" in pml.read_text()
    assert pml.stat().st_mode & 0o777 == 0o640
    assert sorted(p.name for p in tmp_path.iterdir()) == ["model.pml"]
