"""``genom2bip PATH -o DIR``: golden outputs, determinism, and that errors change nothing on disk."""
from __future__ import annotations

import difflib
import os
import subprocess
import sys
from pathlib import Path

import pytest

from genom2bip.cli import main
from runtime.bip2 import parse_file

ROOT = Path(__file__).resolve().parents[1]
GOLDEN = Path(__file__).parent / "golden"

#: (command line as run from the repository root, directory of the committed output)
CASES = [
    (["descriptions/dala", "-o", "gen"], ROOT / "gen" / "dala"),
    (["tests/fixtures/genom3/demo.gen", "-o", "tests/golden"], GOLDEN / "demo"),
    (["tests/fixtures/genom3/counter.gen", "-o", "tests/golden"], GOLDEN / "counter"),
    (["tests/fixtures/genom2/rflex.gen", "-o", "tests/golden"], GOLDEN / "rflex"),
]


def _tree(directory: Path) -> dict[str, str]:
    return {p.name: p.read_text(encoding="utf-8") for p in sorted(directory.iterdir()) if p.is_file()}


def _generate(argv: list[str], out: Path) -> int:
    argv = [a if i == 0 or argv[i - 1] != "-o" else str(out) for i, a in enumerate(argv)]
    cwd = os.getcwd()
    os.chdir(ROOT)
    try:
        return main(argv)
    finally:
        os.chdir(cwd)


@pytest.mark.parametrize("argv,committed", CASES, ids=[c[1].name for c in CASES])
def test_committed_output_is_what_the_generator_produces_now(argv, committed, tmp_path, capsys):
    assert _generate(argv, tmp_path) == 0, capsys.readouterr().err
    fresh = _tree(tmp_path / committed.name)
    assert committed.is_dir(), f"{committed} is missing: run genom2bip {' '.join(argv)}"
    old = _tree(committed)
    assert sorted(fresh) == sorted(old), f"files differ: regenerate with: genom2bip {' '.join(argv)}"
    for name in fresh:
        if fresh[name] != old[name]:
            diff = "".join(difflib.unified_diff(old[name].splitlines(True), fresh[name].splitlines(True),
                                                f"committed/{name}", f"generated/{name}", n=2))
            pytest.fail(f"{committed}/{name} differs from the generator's output "
                        f"(regenerate with: genom2bip {' '.join(argv)}):\n{diff[:6000]}")


def test_generation_is_deterministic(tmp_path):
    assert _generate(["descriptions/dala", "-o", "x"], tmp_path / "a") == 0
    assert _generate(["descriptions/dala", "-o", "x"], tmp_path / "b") == 0
    assert _tree(tmp_path / "a" / "dala") == _tree(tmp_path / "b" / "dala")
    assert not [p for p in (tmp_path / "a").iterdir() if p.name.startswith(".")], "staging directories left behind"


def test_bip_output_reads_back_into_the_same_model(tmp_path):
    from genom2bip.generate import model_of
    from genom2bip.parser import parse_paths
    from genom2bip.rules import all_rules
    from runtime.diagnostics import Reporter

    description = parse_paths([ROOT / "descriptions" / "dala"])
    rules = all_rules(description, ROOT / "descriptions" / "dala" / "rules.yaml", Reporter())
    package, root, _ = model_of(description, "dala", rules)
    assert root == "DALA()"
    assert parse_file(ROOT / "gen" / "dala" / "dala.bip") == package


def test_generated_python_package_builds_the_same_model():
    sys.path.insert(0, str(ROOT / "gen"))
    try:
        import dala  # the committed generated package
        assert dala.package() == parse_file(ROOT / "gen" / "dala" / "dala.bip")
        assert dala.ROOT == "DALA()"
    finally:
        sys.path.remove(str(ROOT / "gen"))
        sys.modules.pop("dala", None)
        sys.modules.pop("dala.model", None)


def test_generated_package_imports_only_runtime():
    import ast

    for path in (ROOT / "gen" / "dala").glob("*.py"):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.level == 0:
                assert node.module.split(".")[0] in ("runtime", "sys"), (path.name, node.module)
            if isinstance(node, ast.Import):
                assert all(a.name.split(".")[0] in ("runtime", "sys") for a in node.names), path.name


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_generated_dala_runs_hundreds_of_steps_without_model_error(seed):
    result = subprocess.run([sys.executable, "-m", "dala", "simulate", "--limit", "600", "--seed", str(seed),
                             "--quiet"], cwd=ROOT / "gen", capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "600 steps, step limit reached"
    assert result.stderr == ""


def test_describe_lists_modules_services_and_connectors():
    result = subprocess.run([sys.executable, "-m", "dala", "describe"], cwd=ROOT / "gen",
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    out = result.stdout
    assert "  NDD: SetParams, SetSpeed, SetDataSource, GoTo, Stop" in out
    assert "  NDD.GoTo.activity: NDD_GoTo_Activity" in out
    assert "  NDD.Stop:start" in out and "  NDD.GoTo:refuse" in out
    assert "  nddPlan: pause::plan, arrived, throw NDD::e_no_goal, throw NDD::e_blocked" in out


# --------------------------------------------------------------------------- errors change nothing


def _snapshot(directory: Path) -> dict[str, bytes]:
    return {str(p.relative_to(directory)): p.read_bytes() for p in sorted(directory.rglob("*")) if p.is_file()}


def test_description_error_writes_nothing(tmp_path, capsys):
    bad = tmp_path / "bad.gen"
    bad.write_text("component bad {\n  task t { period 0 ms; };\n};\n")
    out = tmp_path / "out"
    (out / "bad").mkdir(parents=True)
    (out / "bad" / "keep.txt").write_text("previous output")
    before = _snapshot(out)
    assert main([str(bad), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert f"{bad}:2:" in err and "period" in err
    assert _snapshot(out) == before


def test_missing_input_is_reported_and_nothing_written(tmp_path, capsys):
    out = tmp_path / "out"
    assert main([str(tmp_path / "nope"), "-o", str(out)]) == 2
    assert f"'{tmp_path / 'nope'}' is neither a command (check, generate" in capsys.readouterr().err
    assert main(["generate", str(tmp_path / "nope"), "-o", str(out)]) == 1
    assert "nope: no such file or directory" in capsys.readouterr().err
    assert not out.exists()


def test_unwritable_output_is_an_error_not_a_traceback(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    assert main([str(ROOT / "tests/fixtures/genom3/counter.gen"), "-o", str(blocker)]) == 1
    err = capsys.readouterr().err
    assert err.startswith("genom2bip: error: cannot write") and "Traceback" not in err
    assert blocker.read_text() == "not a directory"


def test_failure_while_writing_keeps_the_previous_output(tmp_path, monkeypatch):
    from genom2bip import generate as gen
    from genom2bip.parser import parse_paths

    description = parse_paths([ROOT / "tests/fixtures/genom3/counter.gen"])
    gen.generate(description, "counter", tmp_path, "counter.gen", "0")
    before = _snapshot(tmp_path)

    def broken(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(Path, "write_text", broken)
    with pytest.raises(OSError):
        gen.generate(description, "counter", tmp_path, "counter.gen", "0")
    monkeypatch.undo()
    assert _snapshot(tmp_path) == before
    assert [p.name for p in tmp_path.iterdir()] == ["counter"]


@pytest.mark.parametrize("name", ["demo", "counter", "rflex"])
def test_golden_controllers_run_without_model_error(name):
    from runtime.codels import any_request, simulated_codels
    from runtime.engine import Engine, RandomPolicy

    package = parse_file(GOLDEN / name / f"{name}.bip")
    externs = simulated_codels(package, seed=7)
    externs.update(any_request())
    summary = Engine(package, f"{name.upper()}()", externs).run(RandomPolicy(7), limit=800)
    assert (summary.outcome, summary.steps) == ("limit", 800), summary.message
