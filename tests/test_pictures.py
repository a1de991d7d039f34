"""Pictures: what each diagram draws is checked against the descriptions and rules it comes from."""
from __future__ import annotations

import re
import struct
import subprocess
import sys
import zlib
from functools import lru_cache
from pathlib import Path

import pytest
from genomkit import engine_for

from genom2bip.back.interface import interface_data
from genom2bip.cli import main
from genom2bip.generate import model_of
from genom2bip.parser import parse_paths
from genom2bip.rules import GUARD_KINDS, all_rules
from runtime.diagnostics import Reporter
from runtime.engine import flatten
from runtime.explore import StateSpace, explore
from runtime.pictures import PictureError, automaton, functional_level, module, outline, render, sequence, structure

ROOT = Path(__file__).resolve().parents[1]
DALA = ROOT / "descriptions" / "dala"
COUNTER = ROOT / "tests" / "fixtures" / "genom3" / "counter.gen"
DINING = ROOT / "tests" / "fixtures" / "verify" / "Dining.bip"

EDGE = re.compile(r'^\s*"([^"]+)" -> "([^"]+)"(?: \[(.*)\])?;$')
NODE = re.compile(r'^\s*"([^"]+)"(?: \[(.*)\])?;$')


def edges(dot: str) -> list[tuple[str, str, str]]:
    """(tail, head, attribute text) of every edge of our DOT output."""
    return [m.groups(default="") for line in dot.splitlines() if (m := EDGE.match(line))]


def nodes(dot: str) -> set[str]:
    return {m.group(1) for line in dot.splitlines() if (m := NODE.match(line)) and not m.group(1).startswith("legend:")}


@lru_cache(maxsize=None)
def dala():
    """(description, rules, flat system, structure) of DALA with its rule file."""
    description = parse_paths(sorted(str(p) for p in DALA.glob("*.gen")))
    reporter = Reporter()
    rules = all_rules(description, DALA / "rules.yaml", reporter)
    assert not reporter.has_errors
    package, root, _ = model_of(description, "dala", rules)
    flat = flatten(package, root)
    return description, rules, flat, structure(flat, interface_data(description, "dala", "descriptions/dala"))


# --------------------------------------------------------------------------- functional level


def _attr(attrs: str, name: str) -> str | None:
    m = re.search(rf'\b{name}="([^"]*)"', attrs)
    return m.group(1) if m else None


def test_functional_level_draws_every_module_poster_and_reader_of_the_descriptions():
    description, _, _, s = dala()
    dot = functional_level(s)
    drawn = edges(dot)
    table = re.compile(r'^\s*"([^"]+)" \[label=<(.*)>, shape="plain"\];$', re.M)
    tables = {m.group(1): m.group(2) for m in table.finditer(dot)}
    assert set(tables) == {c.name for c in description.components}
    for c in description.components:  # one row per service and per poster written, each a port edges can leave
        for sv in c.services:
            assert f'port="s_{sv.name}"' in tables[c.name] and f">{sv.name}<" in tables[c.name]
        for p in c.ports:
            if p.direction == "out":
                assert f'port="p_{p.name}"' in tables[c.name] and f"poster {p.name}" in tables[c.name]
    writes = {(c.name, p.name) for c in description.components for p in c.ports if p.direction == "out"}
    reads = {(w, p.name, c.name) for c in description.components for p in c.ports if p.direction == "in"
             for (w, name) in writes if name == p.name and w != c.name}
    assert reads
    for w, p, r in reads:  # from the poster's row to the module whose codels read it
        assert any((t, h) == (w, r) and _attr(a, "tailport") in (f"p_{p}:e", f"p_{p}") and 'style="dashed"' in a
                   for t, h, a in drawn)
    nddplan = next(a for t, h, a in drawn
                   if (t, h) == ("Aspect", "NDD") and _attr(a, "tailport") in ("p_Obs:e", "p_Obs"))
    assert "nddPlan" in nddplan


def test_functional_level_labels_every_cross_module_rule_with_its_id_from_row_to_row():
    _, rules, _, s = dala()
    drawn = edges(functional_level(s))
    crossing = [r for r in rules if r.kind in GUARD_KINDS for o in r.others if o[0] != r.service[0]]
    assert crossing
    for r in crossing:
        for o in r.others:
            if o[0] != r.service[0]:
                assert any(t == o[0] and h == r.service[0] and r.id in a and "#c0392b" in a
                           and _attr(a, "tailport") == f"s_{o[1]}" and _attr(a, "headport") == f"s_{r.service[1]}"
                           for t, h, a in drawn), r.id
    interrupts = {(r.service, o) for r in rules if r.kind == "interrupts" for o in r.others if o[0] != r.service[0]}
    assert interrupts
    for a, v in interrupts:
        assert any((t, h) == (a[0], v[0]) and "arrowhead=\"tee\"" in attrs and _attr(attrs, "tailport") == f"s_{a[1]}"
                   and _attr(attrs, "headport") == f"s_{v[1]}" for t, h, attrs in drawn), (a, v)


def test_functional_level_legend_is_a_few_lines_of_text_naming_only_what_is_drawn():
    dot = functional_level(dala()[3])
    assert "cluster" not in dot and "legend:" not in dot  # no cluster of sample edges laid out with the graph
    assert "red dashed</b></font>: rule of the rule file" in dot and "orange, bar head" in dot
    assert "green dashed" not in dot  # no constraint of a description crosses modules in DALA


def test_functional_level_of_dala_is_compact_and_its_text_readable(tmp_path):
    """Compact: at most about 1 600 x 800 px (it was 3 237 x 901, a third of it legend; six modules go on two rows);
    no font under 10 pt."""
    dot = functional_level(dala()[3])
    sizes = [float(x) for x in re.findall(r'(?:fontsize="|point-size=")([0-9.]+)', dot)]
    assert sizes and min(sizes) >= 10
    width, height, _ = _png_pixels(render(dot, tmp_path / "level.png").read_bytes())
    assert 800 < width <= 1600 and 300 < height <= 820, (width, height)


def _laid_out_boxes(dot: str) -> tuple[list[tuple[str, tuple[float, ...]]], list[tuple[str, tuple[float, ...]]]]:
    """(edge labels, nodes) of ``dot`` as the layout engine placed them: (text, (x0, y0, x1, y1)) in points.

    A label's box is from its drawing operations (each line's anchor, width and font size: ascent 0.8, descent
    0.25 of the size), an ``xlabel`` as well as a ``label``; a node's from its position and size."""
    import json

    from runtime.pictures.render import layout

    laid = json.loads(layout(dot, "json"))
    labels = []
    for e in laid.get("edges", []):
        size, lines = 10.0, []
        for key in ("_ldraw_", "_hldraw_", "_tldraw_"):
            for op in e.get(key, []):
                if op["op"] == "F":
                    size = op["size"]
                elif op["op"] == "T":
                    (x, y), w = op["pt"], op["width"]
                    x0 = {"c": x - w / 2, "l": x, "r": x - w}[op["align"]]
                    lines.append((op["text"], (x0, y - 0.25 * size, x0 + w, y + 0.8 * size)))
        if lines:
            boxes = [b for _, b in lines]
            box = (min(b[0] for b in boxes), min(b[1] for b in boxes), max(b[2] for b in boxes),
                   max(b[3] for b in boxes))
            labels.append((" / ".join(t for t, _ in lines), box))
    nodes_ = []
    for n in laid.get("objects", []):
        if "pos" in n and "width" in n:
            (x, y), w, h = map(float, n["pos"].split(",")), float(n["width"]) * 36, float(n["height"]) * 36
            nodes_.append((n["name"], (x - w, y - h, x + w, y + h)))
    return labels, nodes_


def _meet(a: tuple[float, ...], b: tuple[float, ...]) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def test_functional_level_of_dala_has_no_label_over_another_nor_over_a_module():
    """Six modules, two to a column: the labels of the edges between two modules of one column (NDD and POM) were
    laid at one spot, over one another; each is now apart from every other label and every module."""
    labels, tables = _laid_out_boxes(functional_level(dala()[3]))
    texts = [t for t, _ in labels]
    assert {"no-reset-while-navigating", "goto-after-pom-run", "aspFuse, aspWaitScan"} <= set(texts)
    assert len(tables) == 6
    over = [(a, b) for i, (a, x) in enumerate(labels) for b, y in labels[i + 1:] if _meet(x, y)]
    over += [(a, m) for a, x in labels for m, y in tables if _meet(x, y)]
    assert over == []


def test_edges_between_modules_of_one_column_are_labelled_beside_them():
    from runtime.pictures.architecture import _labeller

    label = _labeller([["Aspect", "LaserRF"], ["NDD", "POM"]])
    assert label("NDD", "POM", "rule") == {"xlabel": "rule"} and label("POM", "NDD", None) == {"xlabel": None}
    assert label("Aspect", "NDD", "nddPlan") == {"label": "nddPlan"}
    assert _labeller([])("NDD", "POM", "rule") == {"label": "rule"}  # four modules or fewer: no columns


def test_wrapped_labels_keep_every_name_and_stay_short():
    from runtime.pictures.architecture import _wrap

    assert _wrap(["pomWaitOdometry", "pomFix", "pomUpdate"]) == "pomWaitOdometry, pomFix,\npomUpdate"
    assert _wrap(["one"]) == "one" and _wrap([]) == ""
    assert _wrap(["a-very-long-codel-name-indeed", "b"]) == "a-very-long-codel-name-indeed,\nb"


# --------------------------------------------------------------------------- one module


def test_module_picture_has_every_atom_of_the_module_and_the_outside_atoms_its_connectors_bind():
    _, rules, flat, s = dala()
    dot = module(s, "NDD")
    mine = {a.name for a in flat.atoms if a.name.startswith("NDD.")}
    others = {f"{o[0]}.{o[1]}.control" for r in rules if r.service[0] == "NDD" and r.kind in GUARD_KINDS
              for o in r.others if o[0] != "NDD"}
    others |= {f"{r.service[0]}.{r.service[1]}.control" for r in rules if r.kind in (*GUARD_KINDS, "interrupts")
               for o in r.others if o[0] == "NDD" and r.service[0] != "NDD"}
    assert mine | others == nodes(dot) - {"__initial__"}


def test_module_picture_draws_constraints_rules_and_interruptions_distinctly():
    _, rules, _, s = dala()
    drawn = edges(module(s, "NDD"))
    for r in rules:
        if r.service[0] != "NDD" or r.kind not in GUARD_KINDS or r.on_violation != "reject":
            continue
        colour = "#2e8b57" if r.origin == "description" else "#c0392b"
        for o in r.others:
            assert any(t == f"{o[0]}.{o[1]}.control" and h == "NDD.GoTo.control" and r.id in a and colour in a
                       for t, h, a in drawn), (r.id, o)
    stop = [a for t, h, a in drawn if (t, h) == ("NDD.Stop.control", "NDD.GoTo.activity")]
    assert len(stop) == 1 and "interrupts" in stop[0] and "tee" in stop[0]
    assert not any((t, h) == ("NDD.Stop.control", "NDD.GoTo.control") for t, h, _ in drawn)  # cancel goes with abort


def test_module_picture_titles_tasks_not_services_and_leaves_controller_to_activity_unlabelled():
    """A service's frame is untitled (its controller and activity say its name), a task's is titled; the edge from a
    service's controller to its activity carries no label (always start, finish, fail, interrupted)."""
    dot = module(dala()[3], "NDD")
    titles = re.findall(r'^\s*graph \[label="([^"]*)", style="rounded,filled"', dot, re.M)
    assert sorted(titles) == ["", "", "", "", "", "control", "motion"]
    drawn = edges(dot)
    goto = [a for t, h, a in drawn if (t, h) == ("NDD.GoTo.control", "NDD.GoTo.activity")]
    assert goto and all("label=" not in a for a in goto)
    assert any((t, h) == ("NDD.motion.scheduler", "NDD.GoTo.activity") and "exec_start" in a for t, h, a in drawn)


def test_a_module_of_a_small_description_of_our_own():
    description = parse_paths([str(COUNTER)])
    package, root, _ = model_of(description, "counter")
    flat = flatten(package, root)
    s = structure(flat, interface_data(description, "counter", str(COUNTER)))
    name = description.components[0].name
    dot = module(s, name)
    assert {a.name for a in flat.atoms} == nodes(dot) - {"__initial__"}
    services = {f"{name}.{sv.name}" for sv in description.components[0].services}
    assert services <= set(s.owners.values())


# --------------------------------------------------------------------------- one atom


def test_automaton_has_the_places_and_transitions_of_the_atom_type():
    _, _, flat, _ = dala()
    atom = next(a for a in flat.atoms if a.name == "NDD.GoTo.activity")
    dot = automaton(flat, atom.name)
    assert set(atom.type.places) | {"__initial__"} == nodes(dot)
    drawn = edges(dot)
    expected = sum(len(t.sources) * len(t.targets) for t in atom.type.transitions) + len(atom.type.initial.targets)
    assert len(drawn) == expected
    plan = [a for t, h, a in drawn if (t, h) == ("PLAN", "PLAN_YIELD")]
    assert plan and "exec_plan" in plan[0] and "nddPlan" in plan[0]
    assert any(t == "PLAN_YIELD" and h == "ARRIVED" and "yield arrived" in a for t, h, a in drawn)
    assert any(t == "PLAN_YIELD" and h == "FAILED" for t, h, _ in drawn)


def test_unknown_atom_or_module_is_a_key_error():
    _, _, flat, s = dala()
    with pytest.raises(KeyError):
        automaton(flat, "NDD.Nothing.activity")
    with pytest.raises(KeyError):
        module(s, "Nothing")


# --------------------------------------------------------------------------- traces


def test_sequence_diagram_of_a_deadlock_has_one_step_per_interaction_and_the_state_at_the_end():
    from runtime.bip2 import parse_file

    space = StateSpace(parse_file(str(DINING)), "Table3()")
    result = explore(space)
    trace = space.trace_to(result.deadlocks[0])
    dot = sequence(space.engine, trace, ["deadlock 1 of 1", "p0: ONE"])
    steps = [n for n in nodes(dot) if re.fullmatch(r"t\d+", n)]
    assert len(steps) == len(trace) == 3
    for k, step in enumerate(trace, 1):
        assert f'"t{k}" [label="{k}. {step}"' in dot
    heads = {n.split(":", 1)[1] for n in nodes(dot) if n.startswith("head:")}
    assert heads == {p.rsplit(".", 1)[0] for step in trace for p in space.engine.interaction(step.index).ports}
    assert "deadlock 1 of 1\\np0: ONE" in dot


def test_sequence_lifelines_are_modules_across_modules_and_services_within_one():
    _, _, flat, _ = dala()
    engine, _ = engine_for(flat.package, flat.root)
    dot = sequence(engine, ["RFLEX.servo:period", "NDD.GoTo:trigger"], [])
    heads = {n.split(":", 1)[1] for n in nodes(dot) if n.startswith("head:")}
    assert heads == {"RFLEX", "NDD", "POM", "LaserRF", "Aspect"}
    dot = sequence(engine, ["NDD.SetSpeed:start"], [])
    assert {n.split(":", 1)[1] for n in nodes(dot) if n.startswith("head:")} == {"NDD.SetSpeed"}


# --------------------------------------------------------------------------- the outline


def test_describe_outline_lists_flows_interruptions_constraints_and_rules():
    _, rules, _, s = dala()
    text = "\n".join(outline(s))
    assert "Aspect.Obs -> NDD (read by nddPlan)" in text
    for r in rules:
        if r.kind == "interrupts":
            for o in r.others:
                assert f"{r.service[0]}.{r.service[1]} interrupts {o[0]}.{o[1]}" in text
        elif r.kind in GUARD_KINDS:
            for o in r.others:
                line = f"{r.service[0]}.{r.service[1]} guarded by the status of {o[0]}.{o[1]} ("
                assert any(x.strip().startswith(line) and r.id in x for x in text.splitlines()), r.id


# --------------------------------------------------------------------------- rendering


def _png_pixels(data: bytes) -> tuple[int, int, bytes]:
    """Width, height and the decompressed scanlines of a PNG."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat, width, height = 8, b"", 0, 0
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        chunk = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height = struct.unpack(">II", chunk[:8])
        elif kind == b"IDAT":
            idat += chunk
        pos += 12 + length
    return width, height, zlib.decompress(idat)


def test_png_of_the_functional_level_is_a_real_picture(tmp_path):
    out = render(functional_level(dala()[3]), tmp_path / "dala.png")
    width, height, pixels = _png_pixels(out.read_bytes())
    assert width > 800 and height > 300
    assert len(set(pixels)) > 50  # many colours and shades, not a blank page


def test_svg_of_a_module_names_its_services(tmp_path):
    out = render(module(dala()[3], "NDD"), tmp_path / "ndd.svg")
    text = out.read_text()
    assert text.lstrip().startswith("<?xml") or "<svg" in text[:500]
    for service in ("GoTo", "SetSpeed", "SetParams", "SetDataSource", "Stop", "motion"):
        assert f">{service}<" in text


def test_unknown_format_and_missing_layout_engine_write_nothing(tmp_path, monkeypatch):
    with pytest.raises(PictureError, match=r"unknown picture format '\.jpeg'"):
        render("digraph x {}", tmp_path / "x.jpeg")
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))
    monkeypatch.setattr(sys.modules["runtime.pictures.render"], "script_dirs", lambda: [str(tmp_path / "empty")])
    with pytest.raises(PictureError, match="no Graphviz layout engine found: `pip install graphviz-pure`"):
        render("digraph x {}", tmp_path / "x.png")
    assert list(tmp_path.iterdir()) == []
    assert render("digraph x {}", tmp_path / "x.dot").read_text() == "digraph x {}"



def test_the_layout_engine_installed_with_genom2bip_is_found_off_path(tmp_path, monkeypatch):
    """An environment used without being activated has its commands off PATH: graphviz-pure is found all the same."""
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))
    out = render("digraph x { a -> b }", tmp_path / "x.svg")
    assert "<svg" in out.read_text()[:500]

def test_a_failing_layout_leaves_no_file(tmp_path):
    with pytest.raises(PictureError, match="layout engine .* failed"):
        render("digraph { this is not dot", tmp_path / "x.svg")
    assert list(tmp_path.iterdir()) == []


# --------------------------------------------------------------------------- the command line


def test_graph_command_writes_each_view(tmp_path, capsys):
    for args, name in (([], "dala.svg"), (["--module", "POM"], "pom.svg"), (["--atom", "POM.Run.activity"], "run.svg")):
        assert main(["graph", str(DALA), *args, "-o", str(tmp_path / name)]) == 0
        assert (tmp_path / name).stat().st_size > 1000
    assert main(["graph", str(DALA), "--module", "POM"]) == 0
    assert capsys.readouterr().out.count('"POM.Run.control"') >= 1


def test_graph_command_refuses_unknown_names_with_the_nearest_ones(tmp_path, capsys):
    assert main(["graph", str(DALA), "--module", "NDX", "-o", str(tmp_path / "x.png")]) == 1
    assert "no module named 'NDX'; did you mean NDD?" in capsys.readouterr().err
    assert main(["graph", str(DALA), "--atom", "NDD.GoTo.activty", "-o", str(tmp_path / "x.png")]) == 1
    assert "did you mean NDD.GoTo.activity" in capsys.readouterr().err
    assert main(["graph", str(DALA), "-o", str(tmp_path / "x.pdf")]) == 1
    assert "unknown picture format '.pdf'" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_verify_draws_the_counterexample(tmp_path, capsys):
    out = tmp_path / "cex.svg"
    assert main(["verify", str(DINING), "--root", "Table3()", "--quiet", "--trace-picture", str(out)]) == 4
    assert f"wrote {out} (sequence diagram of this trace)" in capsys.readouterr().out
    text = out.read_text()
    assert "deadlock 1 of 1: no interaction enabled" in text and "3. left2" in text


def test_generated_package_describe_prints_the_outline():
    result = subprocess.run([sys.executable, "-m", "dala", "describe"], cwd=ROOT / "gen", capture_output=True,
                            text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    assert "data flow (9):" in result.stdout and "  NDD.Nav -> Planner (read by plnWatch)" in result.stdout
    assert "  NDD.Stop interrupts NDD.GoTo" in result.stdout
    assert "  NDD.GoTo guarded by the status of POM.Run (goto-after-pom-run)" in result.stdout
