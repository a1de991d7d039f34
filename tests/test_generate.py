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


def _as_if_in(tree: dict[str, str], made: Path, committed: Path) -> dict[str, str]:
    """``tree``, generated into ``made``, as it reads when generated into ``committed``: the one line that depends on
    where the package is, its codels folder relative to it, recomputed (and the marker's digest of interface.py)."""
    import hashlib
    import re

    if "interface.py" not in tree:
        return tree
    text = tree["interface.py"]
    found = re.search(r"^    'codels': '([^']*)',$", text, re.M)
    assert found, "interface.py records no codels folder"
    target = os.path.normpath(made / found.group(1))
    moved = Path(os.path.relpath(target, committed)).as_posix()
    text = text[:found.start(1)] + moved + text[found.end(1):]
    old = hashlib.sha256(tree["interface.py"].encode()).hexdigest()
    new = hashlib.sha256(text.encode()).hexdigest()
    out = dict(tree, **{"interface.py": text})
    if ".genom2bip" in out:
        out[".genom2bip"] = out[".genom2bip"].replace(old, new)
    return out


def _regenerate(argv: list[str], committed: Path) -> str:
    """The commands that rewrite a committed output (removed first: after a merge its marker may list other files)."""
    return f"rm -r {committed.relative_to(ROOT)} && genom2bip {' '.join(argv)}"


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
    fresh = _as_if_in(_tree(tmp_path / committed.name), tmp_path / committed.name, committed)
    assert committed.is_dir(), f"{committed} is missing: run genom2bip {' '.join(argv)}"
    old = _tree(committed)
    assert sorted(fresh) == sorted(old), f"files differ: regenerate with: {_regenerate(argv, committed)}"
    for name in fresh:
        if fresh[name] != old[name]:
            diff = "".join(difflib.unified_diff(old[name].splitlines(True), fresh[name].splitlines(True),
                                                f"committed/{name}", f"generated/{name}", n=2))
            pytest.fail(f"{committed}/{name} differs from the generator's output "
                        f"(regenerate with: {_regenerate(argv, committed)}):\n{diff[:6000]}")


def test_generation_is_deterministic(tmp_path):
    assert _generate(["descriptions/dala", "-o", "x"], tmp_path / "a") == 0
    assert _generate(["descriptions/dala", "-o", "x"], tmp_path / "b") == 0
    assert _tree(tmp_path / "a" / "dala") == _tree(tmp_path / "b" / "dala")
    assert not [p for p in (tmp_path / "a").iterdir() if p.name.startswith(".")], "staging directories left behind"


def test_bip_output_reads_back_into_the_same_model(tmp_path, monkeypatch):
    from genom2bip.generate import model_of
    from genom2bip.parser import parse_paths
    from genom2bip.rules import all_rules
    from runtime.diagnostics import Reporter

    monkeypatch.chdir(ROOT)  # @source names description files as the generator was given them: relative
    description = parse_paths([Path("descriptions") / "dala"])
    rules = all_rules(description, Path("descriptions") / "dala" / "rules.yaml", Reporter())
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

    monkeypatch.setattr(Path, "write_bytes", broken)
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


# --------------------------------------------------------------------------- only genom2bip's own output is replaced

COUNTER = ROOT / "tests/fixtures/genom3/counter.gen"


@pytest.fixture
def counter_out(tmp_path, capsys) -> Path:
    """``tmp_path/out``, holding ``counter/`` as generated from counter.gen (console output cleared)."""
    out = tmp_path / "out"
    assert main([str(COUNTER), "-o", str(out)]) == 0
    capsys.readouterr()
    return out


def test_output_that_is_an_input_directory_is_refused(tmp_path, capsys):
    import shutil

    shutil.copytree(ROOT / "descriptions" / "dala", tmp_path / "descriptions" / "dala")
    before = _snapshot(tmp_path)
    assert main([str(tmp_path / "descriptions" / "dala"), "-o", str(tmp_path / "descriptions")]) == 1
    err = capsys.readouterr().err
    assert (f"genom2bip: error: refusing to write {tmp_path}/descriptions/dala: it is the input "
            f"{tmp_path}/descriptions/dala; choose another -o DIR") in err
    assert _snapshot(tmp_path) == before


def test_output_that_contains_an_input_file_is_refused(tmp_path, capsys):
    (tmp_path / "out" / "counter").mkdir(parents=True)
    source = tmp_path / "out" / "counter" / "counter.gen"
    source.write_bytes(COUNTER.read_bytes())
    before = _snapshot(tmp_path)
    assert main([str(source), "-o", str(tmp_path / "out")]) == 1
    assert f"refusing to write {tmp_path}/out/counter: it contains the input {source}" in capsys.readouterr().err
    assert _snapshot(tmp_path) == before


def test_a_directory_genom2bip_did_not_write_is_not_replaced(tmp_path, capsys):
    mine = tmp_path / "out" / "counter"
    mine.mkdir(parents=True)
    (mine / "thesis.tex").write_text("three years of work")
    before = _snapshot(tmp_path)
    assert main([str(COUNTER), "-o", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err
    assert f"refusing to replace {mine}/: genom2bip did not write it (no valid .genom2bip marker)" in err
    assert _snapshot(tmp_path) == before
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["counter"]


def test_regenerating_keeps_a_users_file_and_replaces_only_generated_files(tmp_path, capsys, counter_out):
    out = counter_out
    target = out / "counter"
    marker = (target / ".genom2bip").read_text()
    assert "counter.bip" in marker and "model.py" in marker
    (target / "notes.txt").write_text("my notes")
    (target / "__pycache__").mkdir()
    (target / "__pycache__" / "model.cpython.pyc").write_bytes(b"cache")
    (target / "model.py").unlink()  # a generated file deleted by hand comes back
    capsys.readouterr()
    assert main([str(COUNTER), "-o", str(out)]) == 0
    assert f"kept in {target}/, not written by genom2bip: notes.txt\n" in capsys.readouterr().out
    assert (target / "notes.txt").read_text() == "my notes"
    assert (target / "__pycache__" / "model.cpython.pyc").read_bytes() == b"cache"
    assert (target / "model.py").is_file()
    assert (target / ".genom2bip").read_text() == marker
    assert sorted(p.name for p in out.iterdir()) == ["counter"], "staging or old directories left behind"


def test_a_generated_file_edited_by_hand_is_not_overwritten(tmp_path, capsys, counter_out):
    out = counter_out
    with open(out / "counter" / "model.py", "a") as f:
        f.write("# my fix\n")
    before = _snapshot(tmp_path)
    capsys.readouterr()
    assert main([str(COUNTER), "-o", str(out)]) == 1
    assert (f"refusing to replace {out}/counter/: model.py changed since genom2bip wrote it; "
            f"move it away to regenerate") in capsys.readouterr().err
    assert _snapshot(tmp_path) == before


def test_a_users_file_named_like_a_new_generated_file_is_not_overwritten(tmp_path, capsys, counter_out):
    out = counter_out
    marker = out / "counter" / ".genom2bip"
    marker.write_text("".join(line + "\n" for line in marker.read_text().splitlines() if "interface.py" not in line))
    (out / "counter" / "interface.py").write_text("mine")
    before = _snapshot(tmp_path)
    capsys.readouterr()
    assert main([str(COUNTER), "-o", str(out)]) == 1
    assert "interface.py would be overwritten, and genom2bip did not write it" in capsys.readouterr().err
    assert _snapshot(tmp_path) == before


def test_a_symbolic_link_in_place_of_the_output_is_refused(tmp_path, capsys):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "data").write_text("precious")
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "counter").symlink_to(elsewhere)
    assert main([str(COUNTER), "-o", str(tmp_path / "out")]) == 1
    assert "it is a symbolic link; genom2bip replaces only a directory it wrote itself" in capsys.readouterr().err
    assert (tmp_path / "out" / "counter").is_symlink()
    assert sorted(p.name for p in elsewhere.iterdir()) == ["data"]


def test_a_generated_file_replaced_by_a_link_is_refused_and_its_target_untouched(tmp_path, capsys, counter_out):
    out = counter_out
    victim = tmp_path / "victim.txt"
    victim.write_text("not yours")
    (out / "counter" / "model.py").unlink()
    (out / "counter" / "model.py").symlink_to(victim)
    capsys.readouterr()
    assert main([str(COUNTER), "-o", str(out)]) == 1
    assert "model.py changed since genom2bip wrote it" in capsys.readouterr().err
    assert victim.read_text() == "not yours"


def test_what_a_killed_run_left_is_cleared_only_when_it_is_all_generated(tmp_path, capsys, counter_out):
    out = counter_out
    # A run killed after writing its staging directory, and one killed while moving a user's file back.
    import shutil

    shutil.copytree(out / "counter", out / ".counter.new.abc12345")
    shutil.copytree(out / "counter", out / ".counter.old.def67890")
    (out / ".counter.old.def67890" / "notes.txt").write_text("my notes")
    capsys.readouterr()
    assert main([str(COUNTER), "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert f"warning: {out}/.counter.old.def67890/ was left by an interrupted run" in err
    assert sorted(p.name for p in out.iterdir()) == [".counter.old.def67890", "counter"]
    assert sorted(p.name for p in (out / ".counter.old.def67890").iterdir()) == ["notes.txt"]


def test_an_interrupted_write_leaves_the_previous_output_and_no_staging_directory(tmp_path, monkeypatch):
    from genom2bip import generate as gen
    from genom2bip.parser import parse_paths

    description = parse_paths([COUNTER])
    gen.generate(description, "counter", tmp_path, "counter.gen", "0")
    (tmp_path / "counter" / "notes.txt").write_text("my notes")
    before = _snapshot(tmp_path)
    real = Path.rename

    def interrupted(self, target):
        if ".new." in self.name:
            raise KeyboardInterrupt
        return real(self, target)

    monkeypatch.setattr(Path, "rename", interrupted)
    with pytest.raises(KeyboardInterrupt):
        gen.generate(description, "counter", tmp_path, "counter.gen", "0")
    monkeypatch.undo()
    assert _snapshot(tmp_path) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["counter"]


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes anywhere")
def test_a_read_only_output_directory_is_an_error(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    out.chmod(0o555)
    try:
        assert main([str(COUNTER), "-o", str(out)]) == 1
    finally:
        out.chmod(0o755)
    assert f"cannot write {out}: Permission denied" in capsys.readouterr().err
    assert list(out.iterdir()) == []


# --------------------------------------------------------------------------- odd names and paths


@pytest.mark.parametrize("name,why", [
    ("class", "a Python keyword"),
    ("runtime", "the name of a module the controller imports"),
    ("json", "the name of a module the controller imports"),
])
def test_a_system_name_that_cannot_be_a_package_is_refused(tmp_path, capsys, name, why):
    assert main([str(COUNTER), "-o", str(tmp_path / "out"), "--name", name]) == 1
    assert (f"genom2bip: error: the system name '{name}' gives the Python package '{name}', {why}; "
            f"choose another with --name") in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_system_name_with_path_characters_stays_inside_the_output(tmp_path, capsys):
    out = tmp_path / "deep" / "out"
    assert main([str(COUNTER), "-o", str(out), "--name", "../../escape me"]) == 0
    assert sorted(p.name for p in tmp_path.rglob("*") if p.is_dir()) == ["______escape_me", "deep", "out"]


def test_an_empty_output_name_is_a_usage_error(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main([str(COUNTER), "-o", ""]) == 2
    assert "-o: give a directory (an empty name would write into the current directory)" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_paths_that_are_not_utf8_or_have_spaces_are_written_and_run(tmp_path, capsys):
    source = tmp_path / "odd dir é" / os.fsdecode(b"my robot\xff.gen")
    source.parent.mkdir()
    source.write_bytes(COUNTER.read_bytes())
    out = tmp_path / "out ü"
    assert main([str(source), "-o", str(out)]) == 0, capsys.readouterr().err
    package = out / "my_robot_"
    assert "my robot\\udcff.gen" in (package / "__init__.py").read_text()
    result = subprocess.run([sys.executable, "-m", "my_robot_", "describe"], cwd=out, capture_output=True,
                            text=True, timeout=60, check=False)
    assert result.returncode == 0 and "counter: GetTicks, SetRunning" in result.stdout, result.stderr


def test_a_pipe_given_as_a_description_is_refused_without_reading_it(tmp_path):
    fifo = tmp_path / "pipe.gen"
    os.mkfifo(fifo)
    # In a subprocess with a timeout: reading the pipe would wait for a writer forever.
    for argv, message in ((["check", fifo], f"genom2bip: error: {fifo}: not a regular file"),
                          (["verify", COUNTER, "--property", fifo],
                           f"{fifo}: error: cannot read the property file: not a regular file")):
        result = subprocess.run([sys.executable, "-m", "genom2bip", *map(str, argv)], capture_output=True, text=True,
                                timeout=60, cwd=ROOT, check=False)
        assert (result.returncode, result.stdout) == (1, "") and message in result.stderr


def test_when_the_previous_output_cannot_be_cleared_its_files_stay_and_it_is_said(capsys, monkeypatch, counter_out):
    out = counter_out
    (out / "counter" / "notes.txt").write_text("my notes")
    real = Path.rename

    def read_only(self, target):  # as in a directory the user may not write: its entries cannot move
        if ".old." in self.parent.name:
            raise PermissionError(13, "Permission denied")
        return real(self, target)

    monkeypatch.setattr(Path, "rename", read_only)
    capsys.readouterr()
    assert main([str(COUNTER), "-o", str(out)]) == 1
    monkeypatch.undo()
    err = capsys.readouterr().err
    [old] = [p for p in out.iterdir() if p.name.startswith(".counter.old.")]
    assert f"wrote {out}/counter/, but could not carry everything over from the previous output: {old}/ keeps" in err
    assert (old / "notes.txt").read_text() == "my notes"
    assert (out / "counter" / "model.py").is_file()


def test_a_marker_naming_files_outside_its_directory_is_not_trusted(capsys, counter_out):
    import hashlib

    out = counter_out
    victim = out / "victim.txt"
    victim.write_text("keep me")
    marker = out / "counter" / ".genom2bip"
    digest = hashlib.sha256(victim.read_bytes()).hexdigest()
    marker.write_text(marker.read_text() + f"{digest}  ../victim.txt\n")
    capsys.readouterr()
    assert main([str(COUNTER), "-o", str(out)]) == 1
    assert "genom2bip did not write it (no valid .genom2bip marker)" in capsys.readouterr().err
    assert victim.read_text() == "keep me"


def test_a_dangling_link_as_the_output_directory_is_refused(tmp_path, capsys):
    out = tmp_path / "out"
    out.symlink_to(tmp_path / "nowhere")
    assert main([str(COUNTER), "-o", str(out)]) == 1
    assert f"genom2bip: error: cannot write {out}: it exists and is not a directory" in capsys.readouterr().err
    assert not (tmp_path / "nowhere").exists()
