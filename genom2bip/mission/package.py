"""Which generated package a mission runs on: the one that holds the components its steps name.

A mission under ``descriptions/<system>/missions/`` belongs to the descriptions of ``<system>``: the package
``gen/<system>`` is looked for in the working directory and in every folder above the mission; then any package
under those ``gen`` folders whose components include every component the mission sends requests to.
"""
from __future__ import annotations

import ast
import os
from pathlib import Path

from genom2bip.build.names import ident
from genom2bip.mission.spec import Mission


class NoPackage(Exception):
    """No generated package holds the mission's components; the message says where it looked."""


def components_of(mission: Mission) -> list[str]:
    """The components the mission sends requests to, in the order it first names them."""
    return list(dict.fromkeys(s.target.split(".")[0] for s in mission.steps if s.kind == "send"))


def package_components(directory: Path) -> set[str] | None:
    """The components of the generated package in ``directory`` (read from its interface.py, not imported)."""
    try:
        tree = ast.parse((directory / "interface.py").read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, SyntaxError):
        return None
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "INTERFACE" for t in node.targets):
            try:
                return set(ast.literal_eval(node.value).get("components", {}))
            except (ValueError, AttributeError):
                return None
    return None


def _gen_folders(mission: Mission, cwd: Path) -> list[Path]:
    here = Path(os.path.abspath(mission.path)).parent
    folders = [cwd / "gen"] + [f / "gen" for f in [here, *here.parents]]
    return list(dict.fromkeys(folders))


def mission_system(mission: Mission) -> str:
    """The system a mission file belongs to: ``descriptions/dala/missions/x.yaml`` → ``dala``."""
    here = Path(os.path.abspath(mission.path)).parent
    return (here.parent if here.name == "missions" else here).name


def find_package(mission: Mission, cwd: Path | None = None) -> Path:
    """The generated package the mission runs on; :class:`NoPackage` naming where it looked when there is none."""
    cwd = Path.cwd() if cwd is None else cwd
    wanted = components_of(mission)
    name = ident(mission_system(mission).lower())
    folders = [f for f in _gen_folders(mission, cwd) if f.is_dir()]
    candidates = [f / name for f in folders] + [p for f in folders for p in sorted(f.iterdir()) if p.is_dir()]
    lacking = []
    for candidate in dict.fromkeys(candidates):
        if not (candidate / "__init__.py").is_file():
            continue
        held = package_components(candidate)
        if held is None:
            continue
        missing = [c for c in wanted if c not in held]
        if not missing:
            return candidate
        lacking.append(f"{candidate} has no {', '.join(missing)}")
    looked = ", ".join(str(f) for f in _gen_folders(mission, cwd)[:3]) + ", ..."
    why = "; ".join(lacking[:3]) if lacking else f"no generated package in {looked}"
    raise NoPackage(f"{mission.path}: no generated package holds the mission's components "
                    f"({', '.join(wanted) or 'none named'}): {why}; generate one with `genom2bip DESCRIPTIONS "
                    f"-o gen` beside the mission's descriptions, or give --package DIR")
