"""``genom2bip descriptions/dala -o gen/``: the BIP model as ``.bip`` text and as a runnable Python package.

Output goes to ``<out>/<system>/``: ``<system>.bip`` (one BIP2 package for the
whole functional level) and a Python package that imports only ``runtime``
(``__init__.py``, ``__main__.py``, ``model.py``, and ``interface.py``: the
data the runtime needs to call codels and serve requests).  Everything is written into
a fresh temporary directory first and swapped in at the end, so an error at
any point leaves the output directory as it was; only a directory that
genom2bip wrote itself (its ``.genom2bip`` marker says so) is ever replaced,
and files it did not write are kept (genom2bip.output).  The output is
deterministic: same descriptions, same bytes.  Back ends only turn the model
into text; this module is the one that writes it (``generate``,
``write_bip_file``).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import jinja2

from genom2bip import ir
from genom2bip.back.bip2 import write_package
from genom2bip.back.interface import interface_data, literal
from genom2bip.back.pysource import constructor
from genom2bip.build.functional import FunctionalLevel
from genom2bip.build.names import ident
from genom2bip.output import OutputError, write_file, write_tree
from genom2bip.rules import Rule
from genom2bip.summary import no_component
from runtime.bip2 import validate
from runtime.errors import Genom2bipError
from runtime.model import Package

TEMPLATES = Path(__file__).parent / "templates" / "python"


class GenerateError(Genom2bipError):
    """The model could not be generated; nothing was written."""


@dataclass
class Generated:
    system: str
    directory: Path
    files: list[Path]
    package: Package
    root: str
    kept: list[str] = field(default_factory=list)  # entries of the previous output that were carried over
    leftovers: list[Path] = field(default_factory=list)  # an interrupted run's directories, kept: not all ours


def system_name(paths: list[str]) -> str:
    """The system is named after the first path: ``descriptions/dala`` → ``dala``, ``x/NDD.gen`` → ``NDD``."""
    first = Path(paths[0])
    return first.stem if first.suffix else first.name


def package_name(system: str) -> str:
    """The generated Python package's name; refused when importing it would be a syntax error or hide a module.

    ``python -m <name>`` puts the output directory first on ``sys.path``: a package named ``runtime`` or
    ``json`` would then be imported in place of the module the controller needs.
    """
    import keyword
    import sys

    name = ident(system.lower())
    if keyword.iskeyword(name) or name in ("runtime", "genom2bip") or name in sys.stdlib_module_names:
        why = "a Python keyword" if keyword.iskeyword(name) else "the name of a module the controller imports"
        raise GenerateError(f"the system name '{system}' gives the Python package '{name}', {why}; "
                            f"choose another with --name")
    return name


def model_of(description: ir.Description, system: str,
             rules: list[Rule] | None = None, time=None) -> tuple[Package, str, dict[str, str]]:
    """The package, its root instance and one line of documentation per type.

    ``rules`` are the description's constraints plus a rule file's
    (genom2bip.rules.all_rules); by default the description's alone.
    ``time`` (genom2bip.build.timed.TimeOptions) adds ticks, clocks and observers.
    """
    if not description.components:
        raise GenerateError(no_component(description) + "; a model needs at least one component (or module)")
    level = FunctionalLevel(description, system, rules, time)
    package = level.build()
    problems = [d for d in validate(package) if d.severity == "error"]
    if problems:
        raise GenerateError("the generated model is invalid (a generator bug):\n" +
                            "\n".join(f"  {d.span}: {d.message}" if d.span.line > 0 else f"  {d.message}"
                                      for d in problems))
    root = package.compound_types[-1].name + "()"
    return package, root, level.docs


def _env() -> jinja2.Environment:
    env = jinja2.Environment(loader=jinja2.FileSystemLoader(str(TEMPLATES)), undefined=jinja2.StrictUndefined,
                             trim_blocks=True, lstrip_blocks=True, keep_trailing_newline=True)
    env.filters["pyrepr"] = repr
    return env


def python_files(package: Package, root: str, docs: dict[str, str], module: str, title: str,
                 sources: str, version: str, interface: dict | None = None) -> dict[str, str]:
    """The generated Python package: file name → text (``interface.py`` when ``interface`` data is given)."""
    import runtime.model as model_api

    used: set[str] = set()

    def item(obj, returns: str, doc: str) -> dict:
        used.update(_classes(obj))
        used.add(returns)
        return {"function": obj.name, "returns": returns, "doc": doc, "source": constructor(obj, 4)}

    sections = [
        {"title": "Port types", "entries": [item(p, "PortType", f"Port type {p.name}.") for p in package.port_types]},
        {"title": "Atom types: behaviour", "entries": [
            item(a, "AtomType", docs.get(a.name, f"Atom type {a.name}.")) for a in package.atom_types]},
        {"title": "Connector types: interaction", "entries": [
            item(c, "ConnectorType", _connector_doc(c)) for c in package.connector_types]},
        {"title": "Compound types: the functional level, module by module", "entries": [
            item(c, "CompoundType", f"Compound {c.name}.") for c in package.compound_types]},
    ]
    for f in package.extern_functions:
        used.update(_classes(f))
    used.update(_classes(package.annotations))
    used.add("Package")
    clashes = {i["function"] for s in sections for i in s["entries"]} & set(model_api.__all__)
    if clashes:
        raise GenerateError(f"type names clash with runtime.model classes: {', '.join(sorted(clashes))}")
    env = _env()
    context = {
        "title": title, "version": version, "sources": sources, "module": module,
        "bip_file": f"{package.name}.bip", "root": root, "package_name": package.name, "sections": sections,
        "imports": sorted(used), "externs": [constructor(f, 12) for f in package.extern_functions],
        "package_annotations": [constructor(a, 12) for a in package.annotations],
        "counts": f"{len(package.atom_types)} atom types, {len(package.connector_types)} connector types, "
                  f"{len(package.compound_types)} compound types",
        "has_interface": interface is not None,
        "has_c": interface is not None and any(c.get("c") for c in interface["components"].values()),
        "interface": literal(interface) if interface is not None else "",
    }
    files = {
        "__init__.py": env.get_template("init.py.j2").render(context),
        "__main__.py": env.get_template("main.py.j2").render(context),
        "model.py": env.get_template("model.py.j2").render(context),
    }
    if interface is not None:
        files["interface.py"] = env.get_template("interface.py.j2").render(context)
    return files


def _connector_doc(c) -> str:
    kinds = {"Rendezvous": "all ports together", "RendezvousX": "all ports together, offered to an enclosing connector",
             "Triggered": "the first ports together as a trigger, each receiver joining if it can",
             "TriggeredX": "the first ports together, each other joining if it can, offered to an enclosing connector",
             "BroadcastX": "any of the ports that can, together, offered to an enclosing connector"}
    if c.export is not None and c.export.data:
        return f"Connector type {c.name}: all ports together, their status carried up to an enclosing guard."
    base = c.name.split("_")[0]
    return f"Connector type {c.name}: {kinds.get(base, 'guarded by the status of other services')}."


def _classes(obj) -> set[str]:
    """Names of the runtime.model classes an object is built from."""
    from dataclasses import fields, is_dataclass

    out: set[str] = set()
    if is_dataclass(obj) and not isinstance(obj, type):
        out.add(type(obj).__name__)
        for f in fields(obj):
            out |= _classes(getattr(obj, f.name))
    elif isinstance(obj, (list, tuple)):
        for v in obj:
            out |= _classes(v)
    elif isinstance(obj, dict):
        for v in obj.values():
            out |= _classes(v)
    out.discard("Span")
    return out


def write_bip_file(package: Package, directory: Path | str) -> Path:
    """Write ``<directory>/<package name>.bip`` atomically; nothing is written when the writer refuses the model."""
    text = write_package(package)
    target = Path(directory) / f"{package.name}.bip"
    write_file(target, lambda out: out.write(text))
    return target


def c_codel_files(description: ir.Description, interface: dict, version: str,
                  folder: Path | None = None) -> dict[str, str | bytes]:
    """``<comp>_c_types.h`` and ``lib<comp>_codels.so`` of every component whose codels are C or C++
    (genom2bip.ccompile); the interface learns how to call them (its component's ``c`` entry)."""
    from genom2bip.back.c_types import CMappingError, c_layouts, c_types_header
    from genom2bip.ccompile import CodelBuildError, codel_sources, compile_codels

    files: dict[str, str | bytes] = {}
    for c in description.components:
        sources = codel_sources(description, c, folder)
        if not sources:
            continue
        try:
            header = c_types_header(description, c, c.file, version)
            built = compile_codels(c, sources, header)
            layouts = c_layouts(description, c)
        except (CMappingError, CodelBuildError) as exc:
            raise GenerateError(str(exc)) from None
        files[f"{c.name}_c_types.h"] = header
        files[f"lib{c.name}_codels.so"] = built.library
        interface["components"][c.name]["c"] = {"library": f"lib{c.name}_codels.so", **layouts}
    return files


def generate(description: ir.Description, system: str, out: Path, sources: str, version: str,
             rules: list[Rule] | None = None, inputs: list[str] | None = None, time=None,
             c_codels: Path | None = None) -> Generated:
    """Write ``<out>/<system>/`` atomically (genom2bip.output); returns what was written.

    ``c_codels``: a folder of C/C++ codels, ``<Component>/`` per component, in place of the ``codels/`` folders
    beside the descriptions (genom2bip.ccompile).

    ``inputs`` are the paths read (default: the description's files): the output may not be or contain one.
    ``time`` (genom2bip.build.timed.TimeOptions) adds ticks, clocks and observers.
    """
    package, root, docs = model_of(description, system, rules, time)
    name = package_name(system)
    files = {f"{package.name}.bip": write_package(package)}
    title = f"{system} functional level ({', '.join(c.name for c in description.components)})"
    interface = interface_data(description, system, sources, out / name)
    files.update(c_codel_files(description, interface, version, c_codels))
    files.update(python_files(package, root, docs, name, title, sources, version, interface))

    try:
        written = write_tree(files, out, name, [Path(p) for p in (inputs if inputs is not None else description.files)])
    except OutputError as exc:
        raise GenerateError(str(exc)) from None
    return Generated(system, written.directory, [written.directory / f for f in files], package, root,
                     written.kept, written.leftovers)
