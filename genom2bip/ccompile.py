"""Compiling a component's C and C++ codels into one shared library, against its generated ``<comp>_c_types.h``.

The sources are the component's ``codels/<Component>/`` folder beside its ``.gen``, else every source of
``codels/`` when the component is alone in its folder, else the files of ``codels/`` named ``<Component>*``
(GenoM3's skeleton names them ``<comp>_codels.c``, ``<comp>_<task>_codels.c``).  ``.c`` files go to gcc (gnu99),
``.cc``/``.cpp``/``.cxx`` to g++; the library links with g++ when any file is C++.  Compiler messages keep
the sources' own file:line:column.  The packages the component's ``codels-require`` names are asked of
pkg-config: their ``--cflags`` go to every compilation, their ``--libs`` to the link; a package pkg-config
does not know stops the build at the ``codels-require`` that names it.
"""
from __future__ import annotations

import os
import shlex
import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

from genom2bip import ir
from runtime.ccodels import INCLUDE
from runtime.diagnostics import Diagnostic, DiagnosticError, SourceCache
from runtime.errors import Genom2bipError

#: What the codels call for the wall clock: linked to the controller's clock (runtime/ccodels/clock/wallclock.c).
WRAPPED = ("gettimeofday", "clock_gettime", "time")
WALLCLOCK = INCLUDE.parent / "clock" / "wallclock.c"
#: genom2bip_device(name): the devices the controller offers the codels (runtime/ccodels/devices/devices.c).
DEVICES = INCLUDE.parent / "devices" / "devices.c"
C_SUFFIXES = (".c",)
CXX_SUFFIXES = (".cc", ".cpp", ".cxx", ".C")


class CodelBuildError(Genom2bipError):
    """The codels did not compile or link: the compiler's located messages, or the compiler is missing."""


@dataclass
class Flags:
    """What the ``codels-require`` packages add: compiler flags and linker flags (pkg-config's words)."""

    cflags: list[str]
    libs: list[str]


def required_flags(component: ir.Component, timeout: float = 60.0) -> Flags:
    """pkg-config's ``--cflags`` and ``--libs`` for the component's ``codels-require`` packages (none: empty).

    A package pkg-config does not know (or not in the version asked) is a :class:`DiagnosticError` located at
    the ``codels-require`` string that names it, with pkg-config's own reason.
    """
    packages = list(dict.fromkeys(component.properties.get("codels-require", [])))
    if not packages:
        return Flags([], [])
    if shutil.which("pkg-config") is None:
        raise CodelBuildError(f"the codels of {component.name} require {', '.join(packages)} (codels-require), "
                              "found with pkg-config, which is not installed (Debian: apt-get install pkg-config)")
    for package in packages:
        known = _pkg_config(["--exists", "--print-errors", package], component, timeout)
        if known.returncode != 0:
            span = component.ref_spans.get(f"codels-require:{package}", component.span)
            said = [x.strip() for x in known.stderr.splitlines() if x.strip()]
            reason = next((x for x in said if "has version" in x), said[0] if said else
                          f"pkg-config knows no package {package!r}")  # the version found says most
            where = os.environ.get("PKG_CONFIG_PATH")
            hint = "install its development package, or add the folder of its .pc file to PKG_CONFIG_PATH" + (
                f" (now {where})" if where else "")
            raise DiagnosticError([Diagnostic(span, f"codels-require \"{package}\" of {component.name}: {reason}",
                                              hint=hint)], SourceCache())
    cflags = shlex.split(_pkg_config(["--cflags", *packages], component, timeout).stdout)
    libs = shlex.split(_pkg_config(["--libs", *packages], component, timeout).stdout)
    return Flags(cflags, libs)


def _pkg_config(args: list[str], component: ir.Component, timeout: float) -> subprocess.CompletedProcess:
    try:
        return subprocess.run(["pkg-config", *args], capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        raise CodelBuildError(f"pkg-config {' '.join(args)} (codels of {component.name}) took more than "
                              f"{timeout:.0f} s") from None


@dataclass
class Built:
    """A component's compiled codels: the library's bytes and the sources it was made from."""

    library: bytes
    sources: list[Path]


def codel_sources(description: ir.Description, component: ir.Component, given: Path | None = None) -> list[Path]:
    """The C/C++ sources of ``component`` (none: its codels are Python, or it has none).

    ``given`` (``--c-codels DIR``): ``DIR/<Component>/``, else the files of DIR named ``<Component>*``.
    """
    def sources(d: Path) -> list[Path]:
        return sorted(p for p in d.iterdir() if p.is_file() and p.suffix in C_SUFFIXES + CXX_SUFFIXES)

    if given is not None:
        if (given / component.name).is_dir():
            return sources(given / component.name)
        return [p for p in sources(given) if p.name.startswith(component.name)]
    if not component.file:
        return []
    folder = Path(component.file).parent / "codels"
    if not folder.is_dir():
        return []

    own = folder / component.name
    if own.is_dir():
        return sources(own)
    beside = [c for c in description.components if c.file and Path(c.file).parent == Path(component.file).parent]
    if len(beside) == 1:
        return sources(folder)
    return [p for p in sources(folder) if p.name.startswith(component.name)]


def compile_codels(component: ir.Component, sources: list[Path], header: str, timeout: float = 300.0) -> Built:
    """Compile ``sources`` with ``header`` as ``<comp>_c_types.h`` into a shared library (its bytes)."""
    cxx = any(p.suffix in CXX_SUFFIXES for p in sources)
    needed = ["gcc"] + (["g++"] if cxx else [])
    for tool in needed:
        if shutil.which(tool) is None:
            raise CodelBuildError(f"the codels of {component.name} ({', '.join(str(p) for p in sources)}) need "
                                  f"{tool}, which is not installed (Debian: apt-get install {tool})")
    flags = required_flags(component)
    with tempfile.TemporaryDirectory(prefix=f"genom2bip-{component.name}-") as tmp:
        work = Path(tmp)
        (work / f"{component.name}_c_types.h").write_text(header, encoding="utf-8")
        (work / f"ac{component.name}.h").write_text(autoconf_header(component), encoding="utf-8")
        objects = []
        for k, src in enumerate(sources):
            obj = work / f"{k}_{src.stem}.o"
            tool = "g++" if src.suffix in CXX_SUFFIXES else "gcc"
            std = [] if tool == "g++" else ["-std=gnu99"]
            cmd = [tool, *std, "-fPIC", "-O2", "-Wall", f"-I{work}", f"-I{INCLUDE}", f"-I{src.parent}",
                   *flags.cflags, "-c", str(src), "-o", str(obj)]
            _run(cmd, component, timeout)
            objects.append(str(obj))
        clock = work / "genom2bip_wallclock.o"  # the codels' wall clock can follow the controller's
        _run(["gcc", "-std=gnu99", "-fPIC", "-O2", "-c", str(WALLCLOCK), "-o", str(clock)], component, timeout)
        devices = work / "genom2bip_devices.o"
        _run(["gcc", "-std=gnu99", "-fPIC", "-O2", "-c", str(DEVICES), "-o", str(devices)], component, timeout)
        library = work / f"lib{component.name}_codels.so"
        wrap = [f"-Wl,--wrap={f}" for f in WRAPPED]
        _run(["g++" if cxx else "gcc", "-shared", *wrap, "-o", str(library), *objects, str(clock),
              str(devices), *flags.libs], component, timeout)
        return Built(library.read_bytes(), list(sources))


def autoconf_header(component: ir.Component) -> str:
    """``ac<comp>.h``: what the configure script of genom3's skeleton defines, which its codels include first."""
    version = str(component.properties.get("version", "0.0")).replace('"', "")
    name = component.name
    return (f"/* ac{name}.h: written by genom2bip in place of the configure script's header. */\n"
            f"#ifndef GENOM2BIP_AC_{name}_H\n#define GENOM2BIP_AC_{name}_H\n"
            f'#define PACKAGE "{name}-genom3"\n#define PACKAGE_NAME "{name}-genom3"\n'
            f'#define PACKAGE_VERSION "{version}"\n#define VERSION "{version}"\n'
            f'#define PACKAGE_STRING "{name}-genom3 {version}"\n#endif\n')


def _run(cmd: list[str], component: ir.Component, timeout: float) -> None:
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        raise CodelBuildError(f"compiling the codels of {component.name} took more than {timeout:.0f} s: "
                              f"{' '.join(cmd)}") from None
    if done.returncode != 0:
        lines = [x for x in done.stderr.splitlines() if x.strip()][:40]
        raise CodelBuildError(f"the codels of {component.name} do not compile ({cmd[0]} exit status "
                              f"{done.returncode}):\n" + "\n".join(lines))
