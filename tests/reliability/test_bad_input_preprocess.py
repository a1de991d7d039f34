"""Bad input to the C preprocessor: sizes, devices, recursive includes, encodings; a located error, bounded memory."""
from __future__ import annotations

import os
import shutil

import pytest

from badinputkit import DALA, genom2bip, tree

pytestmark = pytest.mark.reliability

MINIMAL = "component c {\n  ids { long n; };\n};\n"


def _including(tmp_path, name: str, data: bytes):
    """Check a main.gen whose first line includes ``name``, a file holding ``data``: (main, what the run did)."""
    (tmp_path / name).write_bytes(data)
    main = tmp_path / "main.gen"
    main.write_text(f'#include "{name}"\n' + MINIMAL)
    return main, genom2bip("check", main)


def _no_output(tmp_path, done):
    assert "internal error" not in done.err and "Traceback" not in done.err
    assert not (tmp_path / "out").exists()


def test_a_10_mb_description_is_refused_by_its_size_before_it_is_read(tmp_path):
    big = tmp_path / "big.gen"
    with big.open("w") as f:  # one comment of 10 MB, then a component: the shape that cost 500 bytes a byte
        f.write("/*\n" + ("x" * 79 + "\n") * (10 * 1024 * 1024 // 80) + "*/\n" + MINIMAL)
    done = genom2bip(big, "-o", tmp_path / "out")
    assert done.code == 1, done.err
    assert done.err.startswith(f"{big}: error: not read: it holds 10.0 MB of text, more than the 2 MB genom2bip "
                               "reads for a description and its includes\n"), done.err
    _no_output(tmp_path, done)
    assert done.peak_mb < 300, f"{done.peak_mb:.0f} MB to refuse a 10 MB file"


@pytest.mark.parametrize("kind", ["comment", "string"])
def test_a_long_comment_or_string_costs_memory_in_proportion(tmp_path, kind):
    """1.5 MB in one comment or one doc string: before, 810 MB and 560 MB (500 bytes a byte); now about 60 MB."""
    gen = tmp_path / "big.gen"
    n = 1536 * 1024
    if kind == "comment":
        gen.write_text("/*\n" + ("x" * 79 + "\n") * (n // 80) + "*/\n" + MINIMAL)
    else:
        gen.write_text('component c {\n  doc "' + "y" * n + '";\n  ids { long n; };\n};\n')
    done = genom2bip("check", gen)
    assert done.code == 0, done.err
    assert done.out.startswith("component c (genom3)")
    assert done.peak_mb < 250, f"{done.peak_mb:.0f} MB for 1.5 MB of {kind}"


def test_macros_expanding_without_bound_are_stopped_at_the_use(tmp_path):
    """Each macro uses the previous one twice: 2**40 tokens; before, a hang."""
    gen = tmp_path / "laughs.gen"
    gen.write_text("#define A0 x\n" + "".join(f"#define A{i} A{i - 1} A{i - 1}\n" for i in range(1, 41))
                   + "const long k =\n  A40;\n" + MINIMAL)
    done = genom2bip(gen, "-o", tmp_path / "out")
    assert done.code == 1
    assert done.err.startswith(f"{gen}:43:3: error: macro expansion makes more than 1000000 tokens\n"), done.err
    _no_output(tmp_path, done)
    assert done.peak_mb < 500


def test_an_include_of_dev_zero_is_refused_at_its_line(tmp_path):
    main = tmp_path / "main.gen"
    main.write_text('#include "/dev/zero"\n' + MINIMAL)
    done = genom2bip(main, "-o", tmp_path / "out")
    assert done.code == 1
    assert done.err.startswith(f"{main}:1:10: error: cannot include '/dev/zero': not a regular file "
                               "(a device, a pipe or a directory)\n"), done.err
    _no_output(tmp_path, done)
    assert done.peak_mb < 300


def test_an_include_of_a_pipe_is_refused_without_waiting_for_a_writer(tmp_path):
    os.mkfifo(tmp_path / "pipe.idl")
    main = tmp_path / "main.gen"
    main.write_text('\n#include "pipe.idl"\n' + MINIMAL)
    done = genom2bip("check", main)
    assert done.code == 1
    assert done.err.startswith(f"{main}:2:10: error: cannot include 'pipe.idl': not a regular file "), done.err


def test_an_include_larger_than_what_is_left_is_refused_at_its_line(tmp_path):
    main, done = _including(tmp_path, "huge.idl", b"/*" + b"y" * (3 * 1024 * 1024) + b"*/\n")
    assert done.code == 1
    assert done.err.startswith(f"{main}:1:10: error: cannot include 'huge.idl': it holds 3.0 MB of text, more than "
                               "the 2 MB genom2bip reads for a description and its includes\n"), done.err


def test_a_recursive_include_is_refused_with_the_chain_of_includes(tmp_path):
    (tmp_path / "a.idl").write_text('/* a */\n#include "b.idl"\n')
    (tmp_path / "b.idl").write_text('#include "a.idl"\n')
    main = tmp_path / "main.gen"
    main.write_text('#include "a.idl"\n' + MINIMAL)
    done = genom2bip(main, "-o", tmp_path / "out")
    assert done.code == 1
    b = tmp_path / "b.idl"
    assert done.err.startswith(
        f"{b}:1:10: error: recursive #include of 'a.idl': {main}:1 includes a.idl, {tmp_path / 'a.idl'}:2 includes "
        f"b.idl, {b}:1 includes a.idl again\n"), done.err
    _no_output(tmp_path, done)


def test_a_file_including_itself_is_refused(tmp_path):
    main = tmp_path / "main.gen"
    main.write_text(MINIMAL + '#include "main.gen"\n')
    done = genom2bip("check", main)
    assert done.code == 1
    assert done.err.startswith(f"{main}:4:10: error: recursive #include of 'main.gen': {main}:4 includes main.gen "
                               "again\n"), done.err


def test_includes_nested_past_the_limit_are_refused_not_a_recursion_error(tmp_path):
    for i in range(300):  # 300 distinct files, each including the next
        (tmp_path / f"f{i}.idl").write_text(f'#include "f{i + 1}.idl"\n' if i < 299 else "const long z = 1;\n")
    main = tmp_path / "main.gen"
    main.write_text('#include "f0.idl"\n' + MINIMAL)
    done = genom2bip("check", main)
    assert done.code == 1
    assert done.err.startswith(f"{tmp_path / 'f63.idl'}:1:10: error: #include nested more than 64 deep: "
                               f"{main}:1 includes f0.idl, "), done.err
    assert "recursion" not in done.err and "<unknown>" not in done.err


def test_includes_nested_up_to_the_limit_are_read(tmp_path):
    for i in range(64):  # f63 is 64 includes deep
        (tmp_path / f"f{i}.idl").write_text(f'#include "f{i + 1}.idl"\n' if i < 63 else "const long z = 1;\n")
    main = tmp_path / "main.gen"
    main.write_text('#include "f0.idl"\n' + MINIMAL)
    done = genom2bip("check", main)
    assert done.code == 0, done.err


def test_a_latin1_description_names_the_file_line_and_column_that_are_not_utf8(tmp_path):
    main = tmp_path / "robot.gen"
    main.write_bytes(b'component c {\n  doc "d\xe9placement";\n};\n')
    done = genom2bip(main, "-o", tmp_path / "out")
    assert done.code == 1
    assert done.err.startswith(f"{main}:2:9: error: not a UTF-8 text file: byte 0xe9 cannot be read\n"
                               '      doc "d\ufffdplacement";\n'
                               "            ^\n"), done.err
    assert "save it as UTF-8" in done.err
    _no_output(tmp_path, done)


def test_a_latin1_include_is_located_in_the_included_file(tmp_path):
    _, done = _including(tmp_path, "types.idl", b"/* caract\xe8res */\nconst long k = 1;\n")
    assert done.code == 1
    assert done.err.startswith(f"{tmp_path / 'types.idl'}:1:10: error: not a UTF-8 text file: byte 0xe8 cannot "
                               "be read\n"), done.err


def test_dala_still_reads_and_a_refused_input_leaves_the_output_as_it_was(tmp_path):
    src = tmp_path / "dala"
    shutil.copytree(DALA, src)
    out = tmp_path / "gen"
    assert genom2bip(src, "-o", out).code == 0
    before = {p: (out / p).read_bytes() for p in tree(out) if (out / p).is_file()}
    (src / "NDD.gen").write_text((src / "NDD.gen").read_text() + '\n#include "/dev/zero"\n')
    done = genom2bip(src, "-o", out)
    assert done.code == 1 and "cannot include '/dev/zero'" in done.err
    assert {p: (out / p).read_bytes() for p in tree(out) if (out / p).is_file()} == before
