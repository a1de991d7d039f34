"""``<comp>_c_types.h``: the C mapping of fixture components, golden, and compiled as C99 and as C++."""
from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

from genom2bip.back.c_types import CMappingError, c_types_header, cname, cdecl
from genom2bip.parser import parse_paths, parse_text
from runkit import ROOT

FIXTURES = ROOT / "tests" / "fixtures" / "ccodels"
GOLDEN = ROOT / "tests" / "golden" / "c_types"
INCLUDE = ROOT / "runtime" / "ccodels" / "include"
CASES = [("mapping/mapping.gen", "mapping"), ("cdemo/cdemo.gen", "cdemo")]


def header(relative: str, component: str) -> str:
    description = parse_paths([str(FIXTURES / relative)])
    return c_types_header(description, description.component(component), f"tests/fixtures/ccodels/{relative}")


@pytest.mark.parametrize("relative,component", CASES)
def test_the_header_is_the_committed_one(relative, component):
    golden = GOLDEN / f"{component}_c_types.h"
    made = header(relative, component)
    assert golden.is_file(), f"{golden} is missing"
    assert made == golden.read_text(), (f"{golden} differs from the generator's output: rewrite it with "
                                        f"tests/golden/c_types/regenerate.py")


def test_the_mapping_follows_genom3s_rules():
    text = (GOLDEN / "mapping_c_types.h").read_text()
    for line in [
        "typedef struct sequence_geo_point {\n  uint32_t _maximum, _length;\n  geo_point *_buffer;\n"
        "  void (*_release)(void *_buffer);\n} sequence_geo_point;",      # unbounded sequence
        "  const uint32_t _maximum;\n  uint32_t _length;\n  geo_point _buffer[8];",  # bounded sequence
        "typedef char geo_label[32];",                                      # string<32>
        "  char *note;",                                                    # unbounded string
        "typedef struct optional_geo_point {\n  bool _present;\n  geo_point _value;\n} optional_geo_point;",
        "typedef uint32_t geo_shape_kind;\nenum {\n  geo_circle = 0,\n  geo_polygon = 1\n};",
        "struct geo_shape {\n  geo_shape_kind _d;\n  union {\n    double radius;\n    sequence8_geo_point corners;"
        "\n  } _u;\n};",
        "typedef int32_t geo_grid[2][3];",
        "  sequence4_sequence_long layers;",                                # a sequence of sequences
        "const char genom_extern_weak mapping_e_lost_id[] = \"::mapping::e_lost\";",
        "struct mapping_e_lost_detail {\n  geo_point last;\n  char why[64];\n  int32_t tries;\n};",
        "mapping_e_lost(mapping_e_lost_detail *d, genom_context self) {",
        "typedef void mapping_e_empty_detail;",
        "mapping_e_empty(genom_context self) {",
        "  geo_point * (*data)(genom_context self);\n  genom_event (*write)(genom_context self);\n} mapping_Pose;",
        "  geo_point * (*data)(const char *id, genom_context self);\n  genom_event (*write)(const char *id, "
        "genom_context self);\n  genom_event (*open)(const char *id, genom_context self);",
        "  double * (*data)(const char *id, genom_context self);\n  genom_event (*read)(const char *id, "
        "genom_context self);\n} mapping_Ranges;",
        "const char genom_extern_weak mapping_pause_watch[] = \"::mapping::pause::watch\";",
        "struct mapping_ids {\n  geo_scene scene;\n  geo_point here;\n  uint64_t count;\n  uint8_t flags;\n"
        "  int8_t letter;\n  bool on;\n  optional_long budget;\n};",
        "mapStart(geo_point *here, const mapping_Pose *Pose, const genom_context self);",
        "mapFollow(const geo_path *route, geo_path *current, const geo_label name, uint8_t *flags, "
        "const geo_grid cells, optional_long *budget, int8_t *letter, const genom_context self);",
        "mapCheck(const geo_path *route, const geo_label name, const char *note, const genom_context self);",
        "static const int32_t geo_max_points = 8;",
    ]:
        assert line in text, line


def test_names_and_declarators():
    assert cname("::a::b") == "a_b" and cname("unsigned long") == "unsigned_long"
    assert cdecl("int32_t[4]", "x") == "int32_t x[4]" and cdecl("char[8]", "*p") == "char (*p)[8]"
    assert cdecl("char *", "s") == "char *s" and cdecl("double", "d") == "double d"


def test_a_type_c_cannot_express_is_an_error_with_its_place(tmp_path):
    path = tmp_path / "bad.gen"
    path.write_text("component bad {\n  ids { any thing; };\n};\n")
    description = parse_paths([str(path)])
    with pytest.raises(CMappingError) as err:
        c_types_header(description, description.components[0])
    assert f"{path}:2:9" in str(err.value) and "any" in str(err.value)


def test_a_codel_argument_naming_no_variable_is_an_error(tmp_path):
    description = parse_text("component odd {\n  ids { long n; };\n  task t { period 10 ms;\n"
                             "    codel <start> f(ids in nothing) yield ether;\n  };\n};\n", "odd.gen")
    with pytest.raises(CMappingError) as err:
        c_types_header(description, description.components[0])
    assert "odd.gen:4:" in str(err.value) and "codel f: no variable 'nothing'" in str(err.value)


@pytest.mark.parametrize("compiler,flags,suffix", [("gcc", ["-std=c99"], ".c"), ("g++", ["-std=c++11"], ".cc")])
@pytest.mark.parametrize("relative,component", CASES)
def test_the_header_compiles_without_a_warning(tmp_path, compiler, flags, suffix, relative, component):
    if shutil.which(compiler) is None:
        pytest.skip(f"{compiler} is not installed (Debian: apt-get install {'g++' if '+' in compiler else 'gcc'})")
    (tmp_path / f"{component}_c_types.h").write_text(header(relative, component))
    source = tmp_path / f"use{suffix}"
    # two translation units including it: the weak event and exception ids link into one
    source.write_text(f'#include "{component}_c_types.h"\nconst char *first(void) {{ return {component}_ether; }}\n')
    other = tmp_path / f"other{suffix}"
    other.write_text(f'#include "{component}_c_types.h"\n#include "genom3/c/idlsequence.h"\n'
                     f'extern "C" {{ const char *first(void); }}\n' if suffix == ".cc" else
                     f'#include "{component}_c_types.h"\nconst char *first(void);\n')
    other.write_text(other.read_text() + f"int main(void) {{ return first() == {component}_ether ? 0 : 1; }}\n")
    if suffix == ".cc":
        source.write_text(source.read_text().replace("const char *first", 'extern "C" const char *first'))
    run = subprocess.run([compiler, *flags, "-Wall", "-Wextra", "-Werror", f"-I{INCLUDE}", f"-I{tmp_path}",
                          str(source), str(other), "-o", str(tmp_path / "a.out")], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert subprocess.run([str(tmp_path / "a.out")]).returncode == 0  # one id, whichever file names it


def test_genom_sequence_reserve_grows_keeps_and_releases(tmp_path):
    if shutil.which("gcc") is None:
        pytest.skip("gcc is not installed (Debian: apt-get install gcc)")
    (tmp_path / "t.c").write_text(r'''
#include <stdio.h>
#include "genom3/c/idlsequence.h"
typedef struct { uint32_t _maximum, _length; int32_t *_buffer; void (*_release)(void *_buffer); } seq;
static int32_t fixed[2] = {7, 8};
static int released;
static void mine(void *p) { (void)p; released++; }
int main(void) {
  seq s = {2, 2, fixed, mine};
  if (genom_sequence_reserve(&s, 4) != 0) return 1;
  if (released != 1 || s._maximum != 4 || s._length != 2 || s._buffer[0] != 7 || s._buffer[1] != 8) return 2;
  if (s._buffer[2] != 0 || s._buffer[3] != 0 || s._release != free) return 3;
  s._length = 4;
  if (genom_sequence_reserve(&s, 1) != 0 || s._length != 1 || s._maximum != 1 || s._buffer[0] != 7) return 4;
  if (genom_sequence_reserve(&s, 0) != 0 || s._buffer != NULL || s._maximum != 0 || s._length != 0) return 5;
  puts("ok");
  return 0;
}
''')
    run = subprocess.run(["gcc", "-std=c99", "-Wall", "-Werror", f"-I{INCLUDE}", str(tmp_path / "t.c"), "-o",
                          str(tmp_path / "t")], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert subprocess.run([str(tmp_path / "t")], capture_output=True, text=True).stdout == "ok\n"


def test_golden_files_are_listed():
    assert sorted(p.name for p in GOLDEN.glob("*.h")) == sorted(f"{c}_c_types.h" for _, c in CASES)
    assert Path(GOLDEN / "regenerate.py").is_file()


def test_a_used_interfaces_ports_are_the_components_turned_round(tmp_path):
    description = parse_text("module t { struct chunk { long n; }; };\n"
                             "interface source {\n  port out t::chunk Audio;\n};\n"
                             "component sink {\n  uses source;\n  task r { period 10 ms; };\n"
                             "  function Get() { codel sinkGet(port in Audio); };\n};\n", "sink.gen")
    sink = description.component("sink")
    assert [(p.name, str(p.direction)) for p in sink.ports] == [("Audio", "in")]
    text = c_types_header(description, sink)
    assert "typedef struct source_Audio {\n  t_chunk * (*data)(genom_context self);\n  genom_event (*write)" in text
    assert "typedef struct sink_Audio {\n  t_chunk * (*data)(genom_context self);\n  genom_event (*read)" in text
    assert "sinkGet(const sink_Audio *Audio, const genom_context self);" in text


def test_codel_sources_are_the_components_folder_or_all_when_alone_else_by_name(tmp_path):
    from genom2bip.ccompile import codel_sources

    (tmp_path / "one" / "codels").mkdir(parents=True)
    (tmp_path / "one" / "a.gen").write_text("component a { task t { period 10 ms; }; };\n")
    for name in ("a_codels.c", "Date.cc", "notes.txt"):
        (tmp_path / "one" / "codels" / name).write_text("")
    description = parse_paths([str(tmp_path / "one")])
    assert [p.name for p in codel_sources(description, description.component("a"))] == ["Date.cc", "a_codels.c"]
    (tmp_path / "two" / "codels" / "b").mkdir(parents=True)
    (tmp_path / "two" / "a.gen").write_text("component a { task t { period 10 ms; }; };\n")
    (tmp_path / "two" / "b.gen").write_text("component b { task t { period 10 ms; }; };\n")
    (tmp_path / "two" / "codels" / "a_main.c").write_text("")
    (tmp_path / "two" / "codels" / "helper.c").write_text("")
    (tmp_path / "two" / "codels" / "b" / "b.cpp").write_text("")
    description = parse_paths([str(tmp_path / "two")])
    assert [p.name for p in codel_sources(description, description.component("a"))] == ["a_main.c"]
    assert [p.name for p in codel_sources(description, description.component("b"))] == ["b.cpp"]
