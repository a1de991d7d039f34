"""The grammars' LALR tables are kept in the cache (runtime/lalr.py): read back, they parse as the built ones do,
a bad or unwritable cache only means building them again, and nothing but whole files is left in the folder."""
from __future__ import annotations

import errno
import os
from pathlib import Path

import lark
import pytest

from genom2bip.parser.preprocess import preprocess
from genom2bip.parser.dotgen import grammar
from runtime import lalr
from runtime.bip2.syntax import parser as bip2_parser
from runtime.diagnostics import Reporter

ROOT = Path(__file__).resolve().parents[1]
DALA = ROOT / "descriptions" / "dala"


@pytest.fixture
def cache(tmp_path, monkeypatch):
    folder = tmp_path / "cache"
    monkeypatch.setenv("GENOM2BIP_CACHE", str(folder))
    return folder


def no_building(monkeypatch):
    """From here on, a parser whose tables would be built fails (one read from the cache does not build them)."""
    def refuse(self, *args, **kwargs):
        raise AssertionError("the tables were built, not read from the cache")

    monkeypatch.setattr(lark.Lark, "_build_parser", refuse)


def test_tables_kept_by_one_command_are_read_by_the_next_and_parse_every_dala_file_alike(cache, monkeypatch):
    built = grammar.__wrapped__()
    kept = sorted(p.name for p in cache.iterdir())
    assert len(kept) == 1 and kept[0].startswith("lark-") and kept[0].endswith(".tables")  # whole, nothing else
    no_building(monkeypatch)
    read = grammar.__wrapped__()
    files = sorted(DALA.glob("*.gen"))
    assert len(files) >= 5
    for path in files:
        source = preprocess(path, filename=str(path), include_dirs=[str(DALA)], reporter=Reporter())
        # the same tree, with the postlexer given back on reading (identifiers lexed whole after keywords), and the
        # same positions on every node (what a diagnostic's file:line:column is read from)
        mine, theirs = read.parse(source.text), built.parse(source.text)
        assert mine == theirs, path.name
        assert [_where(t) for t in mine.iter_subtrees()] == [_where(t) for t in theirs.iter_subtrees()], path.name
        assert any(t.meta.line > 1 for t in mine.iter_subtrees())


def _where(tree) -> tuple:
    m = tree.meta
    return tree.data, getattr(m, "line", None), getattr(m, "column", None), getattr(m, "end_line", None), \
        getattr(m, "end_column", None)


def test_each_grammar_and_options_have_tables_of_their_own(cache, monkeypatch):
    grammar.__wrapped__()
    bip2_parser.__wrapped__()
    assert len(list(cache.glob("lark-*.tables"))) == 2
    no_building(monkeypatch)
    assert bip2_parser.__wrapped__().parse("package P end") is not None
    other = lalr.tables_path('start: "a"', {"propagate_positions": True})
    assert other != lalr.tables_path('start: "a"', {"propagate_positions": False}) != lalr.tables_path('start: "b"', {})


def test_a_damaged_tables_file_is_built_again_and_replaced(cache, monkeypatch):
    grammar.__wrapped__()
    (kept,) = cache.glob("lark-*.tables")
    whole = kept.read_bytes()
    for damage in (b"", whole[: len(whole) // 2], b"not a pickle" + whole[12:]):
        kept.write_bytes(damage)
        assert grammar.__wrapped__().parse("component c {};") is not None
        assert kept.read_bytes() != damage  # built again and replaced
        assert sorted(cache.iterdir()) == [kept]
    with monkeypatch.context() as m:
        no_building(m)
        assert grammar.__wrapped__().parse("component c {};") is not None  # what replaced it is read


def test_without_a_writable_cache_the_tables_are_built_each_time_and_nothing_is_written(tmp_path, monkeypatch):
    blocker = tmp_path / "a-file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("GENOM2BIP_CACHE", str(blocker / "cache"))
    assert grammar.__wrapped__().parse("component c {};") is not None
    assert blocker.read_text() == "not a folder" and sorted(p.name for p in tmp_path.iterdir()) == ["a-file"]


def test_a_write_that_fails_half_way_leaves_no_partial_file(cache, monkeypatch):
    def full_disk(src, dst):
        raise OSError(errno.ENOSPC, "No space left on device")

    cache.mkdir()
    monkeypatch.setattr(os, "replace", full_disk)  # write_atomic's last step, after the whole file is written
    assert grammar.__wrapped__().parse("component c {};") is not None
    assert list(cache.iterdir()) == []
