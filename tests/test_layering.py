"""The runtime is what generated packages import: it must stand alone, without the generator."""
import ast
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _imported_modules(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
    return names


def test_runtime_sources_never_import_genom2bip():
    offenders = []
    for path in sorted((ROOT / "runtime").rglob("*.py")):
        bad = {m for m in _imported_modules(path) if m == "genom2bip" or m.startswith("genom2bip.")}
        if bad:
            offenders.append(f"{path.relative_to(ROOT)}: {sorted(bad)}")
    assert offenders == []


def test_runtime_imports_in_a_process_without_genom2bip():
    # Block the generator package entirely, then import every runtime module.
    code = (
        "import sys, importlib, pkgutil\n"
        "class Block:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name == 'genom2bip' or name.startswith('genom2bip.'):\n"
        "            raise ImportError('runtime must not import ' + name)\n"
        "sys.meta_path.insert(0, Block())\n"
        "import runtime\n"
        "for m in pkgutil.walk_packages(runtime.__path__, 'runtime.'):\n"
        "    if m.name != 'runtime.__main__':\n"
        "        importlib.import_module(m.name)\n"
        "print('ok')\n"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "ok"


def test_the_controller_never_imports_the_compositional_analysis():
    # verification only: what runs the robot (engine, controller, services, generated code) stays without it
    offenders = []
    for folder in ("runtime/engine", "runtime/controller", "runtime/services", "gen"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            bad = {m for m in _imported_modules(path) if m.startswith("runtime.compositional")}
            if bad:
                offenders.append(f"{path.relative_to(ROOT)}: {sorted(bad)}")
    assert offenders == []


def test_back_ends_return_text_and_only_generate_writes_files():
    # a back end is model -> text; writing (atomically, nothing on error) is genom2bip/generate.py's alone
    writes = {"open", "write_text", "write_bytes", "replace", "mkstemp", "write_file", "write_tree"}
    offenders = []
    for path in sorted((ROOT / "genom2bip" / "back").rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        if "genom2bip.output" in _imported_modules(path):
            offenders.append(f"{path.relative_to(ROOT)}: imports genom2bip.output")
        for node in ast.walk(tree):
            if isinstance(node, ast.Call):
                name = getattr(node.func, "attr", None) or getattr(node.func, "id", None)
                if name in writes:
                    offenders.append(f"{path.relative_to(ROOT)}:{node.lineno}: calls {name}")
    assert offenders == []


def test_the_verification_api_never_imports_the_command_line():
    # genom2bip/verify is a library beside build and back ends: the CLI prints its results, a campaign records them
    offenders = []
    for path in [*sorted((ROOT / "genom2bip" / "verify").rglob("*.py")), ROOT / "genom2bip" / "loading.py"]:
        bad = {m for m in _imported_modules(path) if m == "genom2bip.cli" or m.startswith("genom2bip.cli.")}
        if bad:
            offenders.append(f"{path.relative_to(ROOT)}: {sorted(bad)}")
    assert offenders == []


def test_a_campaign_is_a_client_of_the_verification_api():
    # genom2bip/campaign runs checks through genom2bip.verify: never the command line, never the explorer's, the
    # compiled search's, localization's or the compositional analysis's modules
    inside = ("genom2bip.cli", "runtime.explore", "runtime.native", "runtime.localize", "runtime.compositional",
              "runtime.props", "runtime.engine")
    offenders = []
    for path in sorted((ROOT / "genom2bip" / "campaign").rglob("*.py")):
        bad = {m for m in _imported_modules(path) if any(m == p or m.startswith(p + ".") for p in inside)}
        if bad:
            offenders.append(f"{path.relative_to(ROOT)}: {sorted(bad)}")
    assert offenders == []
