"""How often and how visibly the compiled step is built: one rebuild for a variable that outgrows its field in
every instance of a type, and the compile said on stderr where progress is shown."""
from __future__ import annotations

from genom2bip.loading import TimeSettings
from genom2bip.verify import build_model
from genom2bip.verify.zones import check_timing
from platformkit import FIXTURES, platform_file, verify
from runtime.native import compiled

PAIR = FIXTURES / "Pair.gen"
#: Both tasks' codels may take 9 ms: each scheduler's ``hi`` (9 ticks of 1 ms) outgrows the 4 bits it starts with.
LONG_CODELS = "cores: 2\nexecution:\n  Pair.fast.fast_step: [1 ms, 9 ms]\n  Pair.slow.slow_step: [1 ms, 9 ms]\n"


def test_a_variable_that_outgrows_its_field_is_widened_in_every_instance_at_once(tmp_path, monkeypatch):
    built = []
    real = compiled.build

    def counted(source, *args, **kwargs):
        built.append(len(source))
        return real(source, *args, **kwargs)

    monkeypatch.setattr(compiled, "build", counted)
    monkeypatch.setenv("GENOM2BIP_CACHE", str(tmp_path / "cache"))  # an -O2 build cached by another run is not built
    model = build_model([str(PAIR)], time=TimeSettings(platform=str(platform_file(tmp_path, LONG_CODELS)),
                                                       responses=True))
    results = check_timing(model, ("overrun",), responses=True)
    assert {r.subject: r.verdict.value for r in results if r.check == "observer"} == {
        "period of Pair.fast (10 ms)": "holds", "period of Pair.slow (10 ms)": "holds"}
    assert len(built) == 2, built  # the first build, and one rebuild where each scheduler's 'hi' needed one


def test_a_compile_is_said_on_stderr_with_its_time_when_progress_is_shown(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("GENOM2BIP_CACHE", str(tmp_path / "cache"))
    path = platform_file(tmp_path, "cores: 2\n")
    code, _, err = verify(capsys, PAIR, "--timed", "--platform", path, "--progress")
    assert code == 0
    lines = err.splitlines()
    start = next(k for k, x in enumerate(lines) if x.startswith("genom2bip: compiled step: pair PAIR(): compiling "))
    assert " KB of C (gcc -O" in lines[start] and lines[start].endswith(") ..."), lines
    assert lines[start + 1].startswith("genom2bip: compiled step: pair PAIR(): compiled in "), lines
    code, _, err = verify(capsys, PAIR, "--timed", "--platform", path, "--progress")
    assert "compiling" not in err  # the cache holds it: nothing compiled, nothing said
    code, _, err = verify(capsys, PAIR, "--timed", "--platform", path, "--quiet")
    assert "compil" not in err


def test_a_step_called_state_by_state_is_built_at_O0_and_the_c_search_at_O2(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv("GENOM2BIP_OPT", raising=False)  # the levels users get
    monkeypatch.setenv("GENOM2BIP_CACHE", str(tmp_path / "cache"))

    def levels(err: str) -> list[str]:
        return [x.rsplit("(", 1)[1] for x in err.splitlines() if x.startswith("genom2bip: compiled step: pair ")
                and x.endswith(") ...")]

    path = platform_file(tmp_path, "cores: 2\n")
    code, _, err = verify(capsys, PAIR, "--timed", "--platform", path, "--progress")  # clock zones: single steps
    assert code == 0 and levels(err) == ["gcc -O0) ..."], err
    code, out, err = verify(capsys, PAIR, "--deadlock", "--progress")  # the C search: its build only, no step first
    assert "explored:" in out and levels(err) == ["gcc -O2) ..."], err


def test_a_verify_without_progress_says_nothing_of_compiles_after_one_with_it(tmp_path, capsys, monkeypatch):
    # Who hears of compiles is set per command: a run with --progress in the same process (a test suite, a
    # campaign's worker) must not leave its listener to the next run, which shows no progress.
    monkeypatch.setenv("GENOM2BIP_CACHE", str(tmp_path / "first"))
    code, _, err = verify(capsys, str(PAIR), "--timed", "--schedulability", "--progress")
    assert code == 0 and "compiling" in err
    monkeypatch.setenv("GENOM2BIP_CACHE", str(tmp_path / "second"))  # nothing cached: it compiles again
    code, _, err = verify(capsys, str(PAIR), "--timed", "--schedulability")
    assert code == 0 and err == "", err
