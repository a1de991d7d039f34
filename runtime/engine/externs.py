"""Binding ``extern function`` names to Python callables: a module (object, dotted name or .py path) or a dict."""
from __future__ import annotations

import importlib
import importlib.util
import sys
from pathlib import Path
from types import ModuleType
from typing import Any, Callable, Iterable, Mapping

from runtime.engine.clib import DEFAULTS
from runtime.engine.errors import ExternError, ModelError
from runtime.model import Package


def load_module(spec: str) -> ModuleType:
    """Import a module given by dotted name or by the path of a ``.py`` file."""
    path = Path(spec)
    if spec.endswith(".py") or path.is_file():
        if not path.is_file():
            raise ExternError(f"externs: no file {spec}")
        name = f"_bip_externs_{abs(hash(str(path.resolve())))}"
        mod_spec = importlib.util.spec_from_file_location(name, path)
        if mod_spec is None or mod_spec.loader is None:
            raise ExternError(f"externs: cannot load {spec}")
        module = importlib.util.module_from_spec(mod_spec)
        sys.modules[name] = module
        try:
            mod_spec.loader.exec_module(module)
        except Exception as err:  # the user's module failed while importing
            raise ExternError(f"externs: importing {spec} failed: {type(err).__name__}: {err}") from None
        return module
    try:
        return importlib.import_module(spec)
    except Exception as err:
        raise ExternError(f"externs: cannot import module '{spec}': {type(err).__name__}: {err}") from None


def _lookup(source: Any) -> Callable[[str], Any]:
    if source is None:
        return lambda name: None
    if isinstance(source, str):
        source = load_module(source)
    if isinstance(source, Mapping):
        return source.get
    return lambda name: getattr(source, name, None)


def bind_externs(package: Package, source: Any, needed: Iterable[str] | None = None) -> dict[str, Callable]:
    """Python callables for the package's extern functions, by name.

    ``source`` is a dict, a module, or a module's dotted name or file path; ``printf`` is C's unless
    ``source`` binds it (runtime.engine.clib).
    ``needed`` restricts the check to the functions the model actually calls
    (default: every declared one).  Raises :class:`ExternError` listing every
    name without a callable binding.
    """
    given = _lookup(source)

    def get(name: str):  # the C library's printf when nothing else binds it (runtime.engine.clib)
        fn = given(name)
        return fn if fn is not None else DEFAULTS.get(name)

    names = sorted(set(needed) if needed is not None else {f.name for f in package.extern_functions})
    bound: dict[str, Callable] = {}
    missing = []
    for name in names:
        fn = get(name)
        if fn is None or not callable(fn):
            missing.append(name)
        else:
            bound[name] = fn
    if missing:
        raise ExternError(f"extern function(s) without a Python binding: {', '.join(missing)} "
                          "(give them with --externs MODULE or Engine(..., externs={name: callable}))",
                          tuple(missing))
    return bound


def guarded_call(name: str, fn: Callable) -> Callable:
    """Wrap a binding so that an exception inside it becomes a ModelError naming the extern function."""
    def call(*args):
        try:
            return fn(*args)
        except ModelError:
            raise
        except Exception as err:
            raise ModelError(f"extern function {name}{args!r} raised {type(err).__name__}: {err}") from err
    call.__name__ = f"_x_{name}"
    return call
