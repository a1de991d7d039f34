"""``codels-require``: the packages a component's C codels need, asked of pkg-config for the compiler and linker."""
from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

from genom2bip.cli import main

pytestmark = pytest.mark.skipif(shutil.which("gcc") is None or shutil.which("pkg-config") is None,
                                reason="gcc and pkg-config build codels that require packages (Debian: apt-get "
                                       "install gcc pkg-config)")

GEN = """/* needs: a component whose C codels use a package found by pkg-config. */
component needs {
  lang "c";
  codels-require "g2bfix >= 1.0";
  ids { long answer; };
  function Ask(out answer) {
    codel ndAsk(ids out answer);
  };
};
"""

CODELS = """#include "needs_c_types.h"
#include "g2bfix.h"          /* found through the package's --cflags only */

genom_event
ndAsk(int32_t *answer, const genom_context self)
{
  (void)self;
  *answer = g2bfix_answer() + G2BFIX_BONUS;   /* a function of its library (--libs), a macro of its cflags */
  return genom_ok;
}
"""


def _package(root: Path, version: str = "1.2") -> Path:
    """A small installed package ``g2bfix``: a header, a shared library and its ``.pc`` file under ``root``."""
    inc, lib, pc = root / "include", root / "lib", root / "pc"
    for d in (inc, lib, pc):
        d.mkdir(parents=True)
    (inc / "g2bfix.h").write_text("int g2bfix_answer(void);\n")
    (root / "g2bfix.c").write_text("int g2bfix_answer(void) { return 40; }\n")
    subprocess.run(["gcc", "-shared", "-fPIC", "-o", str(lib / "libg2bfix.so"), str(root / "g2bfix.c")], check=True)
    (pc / "g2bfix.pc").write_text(f"prefix={root}\nName: g2bfix\nDescription: a fixture package\n"
                                  f"Version: {version}\nCflags: -I{inc} -DG2BFIX_BONUS=2\n"
                                  f"Libs: -L{lib} -Wl,-rpath,{lib} -lg2bfix\n")
    return pc


def _component(root: Path, gen: str = GEN) -> Path:
    folder = root / "needs"
    (folder / "codels").mkdir(parents=True)
    (folder / "needs.gen").write_text(gen)
    (folder / "codels" / "needs_codels.c").write_text(CODELS)
    return folder


def test_the_packages_cflags_and_libs_reach_the_compiler_and_the_linker(tmp_path, monkeypatch):
    monkeypatch.setenv("PKG_CONFIG_PATH", str(_package(tmp_path / "pkg")))
    folder = _component(tmp_path)
    out = tmp_path / "gen"
    assert main([str(folder), "-o", str(out)]) == 0

    import importlib.util
    import sys

    spec = importlib.util.spec_from_file_location("needs_pkg_test", out / "needs" / "__init__.py",
                                                  submodule_search_locations=[str(out / "needs")])
    pkg = importlib.util.module_from_spec(spec)
    sys.modules["needs_pkg_test"] = pkg
    spec.loader.exec_module(pkg)
    from runtime.controller import Controller

    controller = Controller(pkg.package(), pkg.ROOT, pkg.INTERFACE, None)
    controller.start()
    try:
        assert controller.binder.missing == []
        req = controller.submit("needs", "Ask")
        final = controller.wait(req.id, timeout=60).final
    finally:
        controller.stop(timeout=30)
    assert final["status"] == "ok", final
    assert final["outputs"] == {"answer": 42}  # 40 from the library, 2 from the cflags


def test_without_the_package_the_codels_would_not_build(tmp_path, monkeypatch):
    """The same codels without the codels-require line: the header is not found (what the pkg-config flags do)."""
    monkeypatch.setenv("PKG_CONFIG_PATH", str(_package(tmp_path / "pkg")))
    folder = _component(tmp_path, GEN.replace('  codels-require "g2bfix >= 1.0";\n', ""))
    assert main([str(folder), "-o", str(tmp_path / "gen")]) == 1
    assert not (tmp_path / "gen").exists()


@pytest.mark.parametrize("version, why", [
    (None, "Package g2bfix was not found in the pkg-config search path."),
    ("0.9", "Package 'g2bfix' has version '0.9', required version is '>= 1.0'")])
def test_a_package_pkg_config_does_not_have_is_one_located_error_and_nothing_is_written(tmp_path, monkeypatch,
                                                                                         capsys, version, why):
    monkeypatch.setenv("PKG_CONFIG_PATH", str(_package(tmp_path / "pkg", version)) if version else
                       str(tmp_path / "nowhere"))
    folder = _component(tmp_path)
    assert main([str(folder), "-o", str(tmp_path / "gen")]) == 1
    err = capsys.readouterr().err
    first = err.strip().splitlines()[0]
    assert first.startswith(f"{folder / 'needs.gen'}:4:18: error: codels-require \"g2bfix >= 1.0\" of needs: ")
    assert why in first
    assert '    codels-require "g2bfix >= 1.0";' in err and "                 ^" in err  # the line, the caret
    assert "PKG_CONFIG_PATH" in err and "Traceback" not in err
    assert not (tmp_path / "gen").exists()


def test_without_pkg_config_the_error_says_so_in_one_line(tmp_path, monkeypatch, capsys):
    folder = _component(tmp_path)
    real = shutil.which

    monkeypatch.setattr(shutil, "which", lambda name, *a, **k: None if name == "pkg-config" else real(name, *a, **k))
    assert main([str(folder), "-o", str(tmp_path / "gen")]) == 1
    err = capsys.readouterr().err.strip()
    assert "the codels of needs require g2bfix >= 1.0 (codels-require), found with pkg-config, which is not " \
           "installed (Debian: apt-get install pkg-config)" in err
    assert len(err.splitlines()) == 1 and not (tmp_path / "gen").exists()


def test_an_interfaces_codels_require_is_located_in_the_interface(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("PKG_CONFIG_PATH", str(tmp_path / "nowhere"))
    folder = _component(tmp_path, GEN.replace('  codels-require "g2bfix >= 1.0";\n', "  provides needy;\n")
                        .replace("/* needs:", 'interface needy {\n  codels-require "g2bfix";\n};\n/* needs:'))
    assert main([str(folder), "-o", str(tmp_path / "gen")]) == 1
    first = capsys.readouterr().err.strip().splitlines()[0]
    assert first.startswith(f"{folder / 'needs.gen'}:2:18: error: codels-require \"g2bfix\" of needs: Package "
                            "g2bfix was not found"), first
    assert not (tmp_path / "gen").exists()
