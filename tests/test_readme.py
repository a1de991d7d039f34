"""Every shell line of the README's "Using it" runs as written, in a fresh folder, within a bound.

Lines that serve a page, open a window, need a server to talk to or run for minutes are checked through their
``--help`` (the command and its options exist); the others run, and their exit status is the one the README's
table gives them.  ``genom2bip`` and ``python`` are this checkout's (``python -m genom2bip``), never an installed
copy.
"""
from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BOUND = 300  # s for any one line: far above what a loaded machine takes (the longest, a mission, about 10 s)

#: Lines checked by their --help, by a piece of their text, and why.
BY_HELP = {
    "gen.dala run": "serves the controller until Ctrl-C",
    "genom2bip call": "talks to the controller that `run` serves",
    "--live": "opens a window on a display",
    "--view": "serves the live page for as long as the mission runs",
    "--timed": "a timed exploration of minutes (docs/verification/time.md)",
    "genom2bip campaign": "a campaign of minutes on Dask workers",
}
#: Lines whose answer is "found" (exit 4): the example model's deadlock (an LTS export checks it too), the timed
#: example's end.
FOUND = ("examples/model.bip --root 'System()' --trace-picture", "examples/model.bip --root 'System()' --method both",
         "python -m runtime explore examples/timed.bip", "examples/model.bip --root 'System()' --traces traces",
         "examples/model.bip --root 'System()' --json", "examples/model.bip --root 'System()' --aut")


def using_it() -> list[str]:
    """The command lines of the "Using it" section's shell blocks, comments and continuation lines left out."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("## Using it", 1)[1].split("\n## ", 1)[0]
    lines = []
    for block in re.findall(r"```sh\n(.*?)```", section, re.S):
        for line in block.splitlines():
            command = line.split(" #", 1)[0].strip()
            if command and not command.startswith("#"):
                lines.append(command)
    return lines


LINES = using_it()


def test_using_it_has_the_lines_the_readme_promises():
    assert len(LINES) >= 30
    placeholders = [line for line in LINES for word in ("model.bip", "timed.bip", "props.mcl", "my.gen", "my.yaml")
                    if re.search(rf"(?<![/\w]){re.escape(word)}", line)]
    assert placeholders == []  # every file a line names is in the repository (examples/)
    # a line run against the wall clock would pass or fail with the machine's load: such lines show their --help
    timed = [line for line in LINES if re.search(r"--real-?time", line) and not any(p in line for p in BY_HELP)]
    assert timed == []


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """A fresh folder with the repository's inputs (descriptions/, examples/) and nothing generated yet."""
    where = tmp_path_factory.mktemp("readme")
    for name in ("descriptions", "examples"):
        (where / name).symlink_to(ROOT / name)
    return where


def _argv(line: str) -> list[str]:
    words = shlex.split(line)
    if words[0] == "genom2bip":
        return [sys.executable, "-m", "genom2bip", *words[1:]]
    assert words[0] == "python", line
    return [sys.executable, *words[1:]]


def _help(argv: list[str]) -> list[str]:
    """The same command up to its first option or value, with --help."""
    head = argv[:3] if argv[2] == "genom2bip" else argv[:4]  # python -m genom2bip VERB / python -m gen.dala run
    return [*head, "--help"]


@pytest.mark.parametrize("line", LINES, ids=[f"{i:02d}" for i in range(len(LINES))])
def test_readme_line_runs(line, folder):
    env = dict(os.environ, PYTHONPATH=f"{folder}{os.pathsep}{ROOT}", MPLBACKEND="Agg")
    env.pop("DISPLAY", None)
    argv = _argv(line)
    why = next((why for piece, why in BY_HELP.items() if piece in line), None)
    if why is not None:
        argv = _help(argv)
    if "gen.dala" in line and not (folder / "gen" / "dala").is_dir():
        generate = [sys.executable, "-m", "genom2bip", "descriptions/dala", "-o", "gen"]
        assert subprocess.run(generate, cwd=folder, env=env, capture_output=True, timeout=BOUND).returncode == 0
    done = subprocess.run(argv, cwd=folder, env=env, capture_output=True, text=True, timeout=BOUND)
    expected = 4 if why is None and any(piece in line for piece in FOUND) else 0
    assert done.returncode == expected, f"{line}\n{done.stdout[-2000:]}\n{done.stderr[-2000:]}"
    assert "Traceback" not in done.stderr and "internal error" not in done.stderr, done.stderr
    if why is not None:
        assert done.stdout.startswith("usage: "), done.stdout[:500]


def tutorial() -> list[tuple[str, int]]:
    """The shell lines of docs/tutorial.md, in order, each with the exit status its comment gives (default 0)."""
    text = (ROOT / "docs" / "tutorial.md").read_text(encoding="utf-8")
    lines = []
    for block in re.findall(r"```sh\n(.*?)```", text, re.S):
        for line in block.splitlines():
            command, _, comment = line.partition(" #")
            status = re.search(r"\bexit (\d+)", comment)
            if command.strip():
                lines.append((command.strip(), int(status.group(1)) if status else 0))
    return lines


def test_every_command_of_the_tutorial_runs_in_order(tmp_path):
    """One fresh folder for the whole walk: each step uses what the one before made (out/gen, out/nowcet.gen)."""
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    env = dict(os.environ, PYTHONPATH=str(ROOT), MPLBACKEND="Agg")
    steps = tutorial()
    assert len(steps) >= 10 and any(status == 4 for _, status in steps)
    for line, status in steps:
        script = f'genom2bip() {{ "{sys.executable}" -m genom2bip "$@"; }}\npython() {{ "{sys.executable}" "$@"; }}\n'
        done = subprocess.run(["bash", "-c", script + line], cwd=tmp_path, env=env, capture_output=True, text=True,
                              timeout=BOUND)
        assert done.returncode == status, f"{line}\n{done.stdout[-2000:]}\n{done.stderr[-2000:]}"
        assert "Traceback" not in done.stderr and "internal error" not in done.stderr, done.stderr
