"""A generated package finds its descriptions' codels from any working directory, wherever it was generated."""
from __future__ import annotations

import os
import subprocess
import sys

from genom2bip.cli import main as genom2bip_main
from runkit import ROOT
from runtime.services.run import find_codels

CODELS = ROOT / "descriptions" / "dala" / "codels"


def _generate(out, monkeypatch) -> None:
    """``genom2bip descriptions/dala -o OUT`` run from the repository, as a user types it."""
    monkeypatch.chdir(ROOT)
    assert genom2bip_main(["descriptions/dala", "-o", str(out)]) == 0


def test_the_interface_records_the_codels_relative_to_the_package(tmp_path, monkeypatch):
    _generate(tmp_path / "out", monkeypatch)
    text = (tmp_path / "out" / "dala" / "interface.py").read_text()
    recorded = os.path.relpath(CODELS, tmp_path / "out" / "dala")
    assert f"'codels': {recorded!r}" in text
    assert (tmp_path / "out" / "dala" / recorded).resolve() == CODELS


def test_a_package_generated_elsewhere_finds_its_codels_from_another_directory(tmp_path, monkeypatch):
    _generate(tmp_path / "out", monkeypatch)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    sys.path.insert(0, str(tmp_path / "out"))
    try:
        text = (tmp_path / "out" / "dala" / "interface.py").read_text()
        scope: dict = {}
        exec(compile(text, "interface.py", "exec"), scope)  # noqa: S102 - the generated data module
        interface = scope["INTERFACE"]
    finally:
        sys.path.remove(str(tmp_path / "out"))
    assert find_codels(interface, None, str(tmp_path / "out" / "dala" / "__main__.py")) == str(CODELS)
    assert find_codels(interface, None, str(tmp_path / "out" / "dala")) == str(CODELS)
    assert find_codels(interface, "given/dir", str(tmp_path / "out" / "dala")) == "given/dir"


def test_python_m_run_from_another_directory_loads_the_codels(tmp_path, monkeypatch):
    _generate(tmp_path / "out", monkeypatch)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(tmp_path / "out"), str(ROOT)]))
    result = subprocess.run([sys.executable, "-m", "dala", "run", "--duration", "0.3", "--quiet"], cwd=elsewhere,
                            capture_output=True, text=True, timeout=120, env=env)
    assert result.returncode == 0, result.stderr
    assert f"codels: {CODELS}" in result.stdout, result.stdout


def test_a_package_moved_away_from_its_codels_runs_without_them_and_says_so(tmp_path):
    interface = {"codels": "../../nowhere/codels"}
    (tmp_path / "pkg").mkdir()
    assert find_codels(interface, None, str(tmp_path / "pkg")) is None
    assert find_codels({"codels": str(tmp_path / "gone")}, None, str(tmp_path / "pkg")) is None
