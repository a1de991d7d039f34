"""A large generated source is compiled once: its code is read back from the cache, the same code, and a cache
file that does not read back is compiled again."""
from __future__ import annotations

import marshal

from runtime.engine import source as source_module
from runtime.engine.source import CACHE_FROM, compile_generated


def _run(code) -> dict:
    ns: dict = {}
    exec(code, ns)  # noqa: S102 - the test's own text
    return ns


def _big(value: int) -> str:
    return "".join(f"def f{k}():\n    return {k}\n" for k in range(CACHE_FROM // 20)) + f"answer = {value}\n"


def test_a_large_source_is_compiled_once_then_read_back(tmp_path, monkeypatch):
    monkeypatch.setenv("GENOM2BIP_CACHE", str(tmp_path))
    text = _big(42)
    compiled = []
    real = compile

    def counting(*args, **kw):
        compiled.append(args[1])
        return real(*args, **kw)

    monkeypatch.setattr(source_module, "compile", counting, raising=False)
    first = compile_generated(text, "demo step")
    kept = list(tmp_path.glob("py-*.marshal"))
    assert len(kept) == 1 and len(compiled) == 1
    again = compile_generated(text, "demo step")
    assert len(compiled) == 1, "read back, not compiled again"
    assert again.co_filename == first.co_filename and again.co_filename.startswith("<demo step #")
    assert _run(again)["answer"] == 42 and _run(again)["f7"]() == 7
    assert compile_generated(_big(43), "demo step").co_filename != first.co_filename
    assert _run(compile_generated(_big(43), "demo step"))["answer"] == 43


def test_a_cache_file_that_does_not_read_back_is_compiled_again(tmp_path, monkeypatch):
    monkeypatch.setenv("GENOM2BIP_CACHE", str(tmp_path))
    text = _big(5)
    compile_generated(text, "demo step")
    (kept,) = tmp_path.glob("py-*.marshal")
    kept.write_bytes(kept.read_bytes()[:100])  # cut short
    assert _run(compile_generated(text, "demo step"))["answer"] == 5
    assert isinstance(marshal.loads(kept.read_bytes()), type(compile("0", "x", "eval")))  # written again whole
    kept.write_bytes(marshal.dumps(compile("answer = 99", "<other>", "exec")))  # another source's code
    assert _run(compile_generated(text, "demo step"))["answer"] == 5


def test_small_sources_and_an_unwritable_cache_are_compiled_as_before(tmp_path, monkeypatch):
    blocked = tmp_path / "file"
    blocked.write_text("not a directory")
    monkeypatch.setenv("GENOM2BIP_CACHE", str(blocked / "cache"))
    assert _run(compile_generated("answer = 1\n", "small"))["answer"] == 1
    assert _run(compile_generated(_big(3), "demo step"))["answer"] == 3
    monkeypatch.setenv("GENOM2BIP_CACHE", str(tmp_path / "c"))
    compile_generated("answer = 1\n", "small")
    assert not (tmp_path / "c").exists()
