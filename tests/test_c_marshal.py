"""Plain values to C data and back (runtime/ccodels/marshal.py), and that its structures are the header's."""
from __future__ import annotations

import ctypes
import shutil
import subprocess

import pytest

from genom2bip.back.c_types import CMapping, c_layouts, c_types_header, layout
from genom2bip.ir import NamedType
from genom2bip.parser import parse_paths
from runkit import ROOT
from runtime.ccodels.marshal import Layouts

MAPPING = ROOT / "tests" / "fixtures" / "ccodels" / "mapping" / "mapping.gen"
INCLUDE = ROOT / "runtime" / "ccodels" / "include"
SCENE = {"name": "hall", "note": "a note", "route": [{"x": 1.0, "y": 2.0}, {"x": 3.0, "y": 4.0}],
         "layers": [[1, 2], [], [3]], "goal": {"x": 5.0, "y": 6.0}, "outline": {"corners": [{"x": 0.0, "y": 1.0}]},
         "cells": [[1, 2, 3], [4, 5, 6]], "tags": ["a", "bb"]}


@pytest.fixture(scope="module")
def mapping():
    description = parse_paths([str(MAPPING)])
    return description, description.component("mapping")


def test_every_kind_of_value_goes_to_c_and_back(mapping):
    description, component = mapping
    layouts = Layouts(c_layouts(description, component)["types"])
    keep: list = []
    scene = ["ref", "geo::scene"]
    assert layouts.value(scene, layouts.new(scene, SCENE, keep)) == SCENE
    other = dict(SCENE, goal=None, outline={"radius": 2.5}, name="x" * 40, tags=["a", "b", "c"])
    back = layouts.value(scene, layouts.new(scene, other, keep))
    assert back["goal"] is None and back["outline"] == {"radius": 2.5}
    assert back["name"] == "x" * 31 and back["tags"] == ["a", "b"]  # string<32> keeps 31 chars; tags holds 2
    assert layouts.value(["ref", "geo::shape_kind"], layouts.scalar(["ref", "geo::shape_kind"], "polygon", keep)) \
        == "polygon"
    assert layouts.value(["b", "char"], layouts.scalar(["b", "char"], "z", keep)) == "z"


def test_the_bindings_structures_have_the_headers_sizes_and_offsets(mapping, tmp_path):
    if shutil.which("gcc") is None:
        pytest.skip("gcc is not installed (Debian: apt-get install gcc)")
    description, component = mapping
    layouts = Layouts(c_layouts(description, component)["types"])
    (tmp_path / "mapping_c_types.h").write_text(c_types_header(description, component))
    fields = ["name", "note", "route", "layers", "goal", "outline", "cells", "tags"]
    lines = [f'printf("%zu\\n", offsetof(geo_scene, {f}));' for f in fields]
    (tmp_path / "sizes.c").write_text('#include <stdio.h>\n#include <stddef.h>\n#include "mapping_c_types.h"\n'
                                      "int main(void) {\n  printf(\"%zu\\n\", sizeof(geo_scene));\n"
                                      "  printf(\"%zu\\n\", sizeof(mapping_ids));\n  " + "\n  ".join(lines) +
                                      "\n  return 0;\n}\n")
    built = subprocess.run(["gcc", "-std=c99", f"-I{INCLUDE}", f"-I{tmp_path}", str(tmp_path / "sizes.c"), "-o",
                            str(tmp_path / "sizes")], capture_output=True, text=True)
    assert built.returncode == 0, built.stderr
    printed = [int(x) for x in subprocess.run([str(tmp_path / "sizes")], capture_output=True, text=True).stdout.split()]
    scene = layouts.ctype(["ref", "geo::scene"])
    assert printed[0] == ctypes.sizeof(scene)
    assert printed[2:] == [getattr(scene, f).offset for f in fields]
    named: dict = {}
    ids = layout(CMapping(description), NamedType("mapping::ids"), named)  # the whole IDS: every kind of member
    assert printed[1] == ctypes.sizeof(Layouts(named).ctype(ids))


def test_a_multiple_out_port_handle_writes_opens_and_closes_its_elements():
    from runtime.ccodels.library import Port

    port = Port(Layouts({}), ["b", "double"], "out", True, {"left": 1.0, "gone": 3.0})
    handle = port.handle
    assert ctypes.c_double.from_address(handle.data(b"left", None)).value == 1.0  # the element's current value
    ctypes.c_double.from_address(handle.data(b"right", None)).value = 2.5
    assert handle.rw(b"right", None) is None  # genom_ok
    assert handle.close(b"gone", None) is None
    assert port.published() == (True, {"left": 1.0, "right": 2.5})
    untouched = Port(Layouts({}), ["b", "double"], "in", False, 4.0)
    assert ctypes.c_double.from_address(untouched.handle.data(None)).value == 4.0
    assert untouched.handle.rw(None) is None and untouched.published() == (False, None)  # read() publishes nothing
