"""The tree stays clean under the ruff settings pinned in pyproject.toml (line length 120, pycodestyle, pyflakes)."""
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_ruff_finds_nothing():
    ruff = shutil.which("ruff")
    argv = [ruff] if ruff else [sys.executable, "-m", "ruff"]
    proc = subprocess.run([*argv, "check", "--no-cache", "."], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_the_line_length_is_pinned(tmp_path):
    long_line = tmp_path / "long.py"
    long_line.write_text("x = '" + "a" * 130 + "'\n")
    ruff = shutil.which("ruff")
    argv = [ruff] if ruff else [sys.executable, "-m", "ruff"]
    proc = subprocess.run([*argv, "check", "--no-cache", "--config", str(ROOT / "pyproject.toml"), str(long_line)],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 1 and "E501" in proc.stdout, proc.stdout + proc.stderr
