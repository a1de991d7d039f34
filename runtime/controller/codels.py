"""Finding Python codels by name: a codels package with one module per component.

``descriptions/dala/codels/NDD.py`` defines NDD's codels (``def nddPlan(...)``);
a function in the package's ``__init__.py`` serves every component that has
no module of its own defining it.  The package is a directory (with or
without ``__init__.py``), a dotted module name, a module object, or a dict
``{component: module-or-dict}`` (tests).
"""
from __future__ import annotations

import hashlib
import importlib
import importlib.util
import sys
import types
from pathlib import Path
from typing import Any, Callable, Mapping


class CodelSource:
    """The codel functions of every component, or why one cannot be had (to report with the codel's name)."""

    def __init__(self, where: str, modules: dict[str, Any], common: Any = None,
                 problems: dict[str, str] | None = None) -> None:
        self.where = where
        self.modules = modules
        self.common = common
        self.problems = problems or {}

    def find(self, component: str, codel: str) -> Callable | None:
        for holder in (self.modules.get(component), self.common):
            if holder is None:
                continue
            fn = holder.get(codel) if isinstance(holder, Mapping) else getattr(holder, codel, None)
            if callable(fn):
                return fn
        return None

    def why_missing(self, component: str, codel: str) -> str:
        """A sentence saying where ``codel`` was looked for."""
        if component in self.problems:
            return f"codel {codel} is missing: {self.problems[component]}"
        if self.where == "":
            return f"codel {codel} is missing: no codels were given (--codels DIR)"
        return f"codel {codel} is missing: no function {codel} in {self.where} ({component}.py or __init__.py)"


def no_codels() -> CodelSource:
    return CodelSource("", {})


def load_codels(source: Any, components: list[str]) -> CodelSource:
    """The codels of ``components`` from a directory, a dotted module name, a module or a dict."""
    if source is None:
        return no_codels()
    if isinstance(source, Mapping):
        return CodelSource("the codels given", dict(source))
    if isinstance(source, types.ModuleType):
        return _from_package(source, components, source.__name__)
    path = Path(source)
    if path.is_dir():
        return _from_directory(path, components)
    try:
        package = importlib.import_module(str(source))
    except Exception as err:  # noqa: BLE001 - reported, the controller still runs
        return CodelSource(str(source), {}, problems={c: f"cannot import {source}: {type(err).__name__}: {err}"
                                                       for c in components})
    return _from_package(package, components, str(source))


def _from_directory(path: Path, components: list[str]) -> CodelSource:
    """Import ``path`` as a package under a private name, so its modules may import each other relatively."""
    name = "_codels_" + hashlib.sha1(str(path.resolve()).encode()).hexdigest()[:12]
    init = path / "__init__.py"
    problems: dict[str, str] = {}
    if name in sys.modules:
        package = sys.modules[name]
    elif init.is_file():
        spec = importlib.util.spec_from_file_location(name, init, submodule_search_locations=[str(path)])
        package = importlib.util.module_from_spec(spec)
        sys.modules[name] = package
        try:
            spec.loader.exec_module(package)
        except Exception as err:  # noqa: BLE001
            del sys.modules[name]
            reason = f"importing {init} failed: {type(err).__name__}: {err}"
            return CodelSource(str(path), {}, problems={c: reason for c in components})
    else:
        package = types.ModuleType(name)
        package.__path__ = [str(path)]
        sys.modules[name] = package
    modules = {}
    for c in components:
        if (path / f"{c}.py").is_file():
            try:
                modules[c] = importlib.import_module(f"{name}.{c}")
            except Exception as err:  # noqa: BLE001
                problems[c] = f"importing {path / (c + '.py')} failed: {type(err).__name__}: {err}"
    return CodelSource(str(path), modules, package if init.is_file() else None, problems)


def _from_package(package: types.ModuleType, components: list[str], where: str) -> CodelSource:
    modules = {}
    problems: dict[str, str] = {}
    for c in components:
        try:
            modules[c] = importlib.import_module(f"{package.__name__}.{c}")
        except ModuleNotFoundError as err:
            if err.name != f"{package.__name__}.{c}":
                problems[c] = f"importing {package.__name__}.{c} failed: {err}"
        except Exception as err:  # noqa: BLE001
            problems[c] = f"importing {package.__name__}.{c} failed: {type(err).__name__}: {err}"
    return CodelSource(where, modules, package, problems)


def c_devices(source: CodelSource) -> dict[str, Callable[[], Any]]:
    """The devices the Python codels offer C codels: ``C_DEVICES = {name: make}`` in any of their modules, ``make()``
    giving the device's table of C-callable functions (a ctypes object; genom2bip/device.h)."""
    out: dict[str, Callable[[], Any]] = {}
    for holder in [source.common, *source.modules.values()]:
        offered = getattr(holder, "C_DEVICES", None) if holder is not None and not isinstance(holder, Mapping) \
            else None
        if isinstance(offered, Mapping):
            out.update(offered)
    return out


def with_c_codels(source: CodelSource, interface: dict[str, Any], clock: Any = None) -> CodelSource:
    """``source`` with the C codel libraries the interface names (runtime.ccodels): a component's C codels
    serve it in place of Python ones; a library that cannot be loaded is reported per codel.  On a virtual
    ``clock`` the C codels' wall clock is the controller's.  The devices the Python codels offer (``C_DEVICES``,
    :func:`c_devices`) are the C codels' ``genom2bip_device()``."""
    if not any(spec.get("c") for spec in interface["components"].values()):
        return source
    from runtime.ccodels import c_codels

    found, problems, loaded = c_codels(interface, clock=clock, devices=c_devices(source))
    source.modules.update(found)
    source.problems.update(problems)
    if loaded:
        source.where = ", ".join(x for x in [source.where, *loaded] if x)
    return source
