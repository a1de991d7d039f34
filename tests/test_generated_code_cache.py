"""A generated source is compiled once per text without its comments: its code is kept for the process and, for a
large one, read back from the cache in later processes, under the new source's name; what is not a comment always
reaches the code."""
from __future__ import annotations

import marshal
import traceback

import pytest

from runtime.engine import source as source_module
from runtime.engine.source import CACHE_FROM, compile_generated


def _run(code) -> dict:
    ns: dict = {}
    exec(code, ns)  # noqa: S102 - the test's own text
    return ns


def _big(value: int, where: str = "/tmp/a/client.yaml") -> str:
    body = "".join(f"def f{k}():  # from {where}:{k}:1\n    return {k}\n" for k in range(CACHE_FROM // 30))
    return body + f"answer = {value}  # the answer\nhashed = 'x  # not a comment'\n" \
                  "def fails():\n    raise ValueError('here')  # from " + where + "\n"


@pytest.fixture
def compiles(tmp_path, monkeypatch):
    monkeypatch.setenv("GENOM2BIP_CACHE", str(tmp_path))
    made = []
    real = compile

    def counting(*args, **kw):
        made.append(args[1])
        return real(*args, **kw)

    monkeypatch.setattr(source_module, "compile", counting, raising=False)
    source_module._kept.clear()  # as in a new process
    yield made
    source_module._kept.clear()


def test_sources_differing_in_comments_share_one_compile(tmp_path, compiles):
    first = compile_generated(_big(42), "demo step")
    again = compile_generated(_big(42, "/tmp/b/client.yaml"), "demo step")
    assert len(compiles) == 1 and len(list(tmp_path.glob("py-*.marshal"))) == 1
    assert again.co_filename != first.co_filename and again.co_filename.startswith("<demo step #")
    ns = _run(again)
    assert (ns["answer"], ns["f7"](), ns["hashed"]) == (42, 7, "x  # not a comment")
    assert ns["f7"].__code__.co_filename == again.co_filename
    with pytest.raises(ValueError) as err:
        ns["fails"]()
    last = traceback.extract_tb(err.value.__traceback__)[-1]
    assert last.filename == again.co_filename and "/tmp/b/client.yaml" in last.line  # the new source's own line
    other = compile_generated(_big(43), "demo step")
    assert len(compiles) == 2 and _run(other)["answer"] == 43


def test_a_cache_file_that_does_not_read_back_is_compiled_again(tmp_path, compiles):
    text = _big(5)
    compile_generated(text, "demo step")
    (kept,) = tmp_path.glob("py-*.marshal")
    kept.write_bytes(kept.read_bytes()[:100])  # cut short
    source_module._kept.clear()  # a later process
    assert _run(compile_generated(text, "demo step"))["answer"] == 5
    assert len(compiles) == 2
    assert _run(marshal.loads(kept.read_bytes()))["answer"] == 5  # written again whole


def test_small_sources_open_strings_and_an_unwritable_cache_are_compiled_as_before(tmp_path, monkeypatch,
                                                                                    compiles):
    blocked = tmp_path / "file"
    blocked.write_text("not a directory")
    monkeypatch.setenv("GENOM2BIP_CACHE", str(blocked / "cache"))
    assert _run(compile_generated(_big(3), "demo step"))["answer"] == 3
    monkeypatch.setenv("GENOM2BIP_CACHE", str(tmp_path / "c"))
    assert _run(compile_generated("answer = 1  # one\n", "small"))["answer"] == 1
    text = 'doc = """first\nkept  # inside a string\n"""\n' + _big(4)
    assert _run(compile_generated(text, "demo step"))["doc"] == "first\nkept  # inside a string\n"
    assert not (tmp_path / "c").exists()


def test_a_process_compiles_a_text_once_and_forgets_the_oldest_past_its_bound(tmp_path, monkeypatch, compiles):
    small = "answer = 1  # from /tmp/a/client.yaml\n"
    first = compile_generated(small, "small step")
    again = compile_generated(small.replace("/tmp/a", "/tmp/b"), "small step")
    same = compile_generated(small, "small step")
    assert len(compiles) == 1 and not list(tmp_path.glob("py-*.marshal"))  # a small text is kept in memory only
    assert same is first and again.co_filename != first.co_filename and _run(again)["answer"] == 1
    assert again.co_filename.startswith("<small step #")
    big = _big(6)
    monkeypatch.setattr(source_module, "KEPT_CHARS", 100)  # room for the small text alone: the newest always stays
    compile_generated(big, "demo step")
    compile_generated(small, "small step")  # the older one, let go for the big text
    assert len(compiles) == 3
    compile_generated(small, "small step")
    assert len(compiles) == 3
