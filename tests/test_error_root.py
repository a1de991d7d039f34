"""One root exception for the product, turned into an exit status in one place."""
from __future__ import annotations

import pytest

from genom2bip.cli import command, verbs
from runtime.diagnostics import Diagnostic, DiagnosticError, Span
from runtime.engine.errors import ModelError
from runtime.errors import Genom2bipError


def _run_raising(monkeypatch, exc: BaseException) -> int:
    """``main`` on a verb whose body raises ``exc``."""
    def boom(args):
        raise exc
    monkeypatch.setitem(command.VERBS, "boom", verbs.Verb("boom", "raise", boom, None))
    return command.main(["boom"])


def test_a_model_error_escaping_a_verb_is_a_message_and_status_1(monkeypatch, capsys):
    assert _run_raising(monkeypatch, ModelError("non-determinism", atom="a.b")) == verbs.EXIT_ERRORS
    err = capsys.readouterr().err
    assert err == "genom2bip: error: non-determinism | atom a.b\n"


def test_diagnostics_escaping_a_verb_are_rendered_with_their_position(monkeypatch, capsys):
    diag = Diagnostic(Span("m.gen", 3, 7), "unknown type 'x'")
    assert _run_raising(monkeypatch, DiagnosticError([diag])) == verbs.EXIT_ERRORS
    assert capsys.readouterr().err.startswith("m.gen:3:7: error: unknown type 'x'")


def test_failure_keeps_its_code_and_a_bug_stays_an_internal_error(monkeypatch, capsys):
    assert _run_raising(monkeypatch, verbs.Failure(verbs.EXIT_USAGE)) == verbs.EXIT_USAGE
    assert capsys.readouterr().err == ""
    assert _run_raising(monkeypatch, KeyError("k")) == verbs.EXIT_INTERNAL
    assert "internal error: KeyError" in capsys.readouterr().err


@pytest.mark.parametrize("path", ["genom2bip.generate:GenerateError", "genom2bip.output:OutputError",
                                  "genom2bip.back.bip2:BipWriteError", "genom2bip.build.split:SplitError",
                                  "runtime.explore:ExploreError", "runtime.engine.errors:FlattenError"])
def test_the_product_errors_share_the_root(path):
    import importlib

    module, name = path.split(":")
    assert issubclass(getattr(importlib.import_module(module), name), Genom2bipError)
