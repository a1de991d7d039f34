"""Runs: policies, limits, deadlocks, traces (JSON lines and console), the generated source."""
import io
import json

from enginekit import engine

from runtime.engine import (
    ConsoleTracer, InteractivePolicy, JsonlTracer, MemoryTracer, MultiTracer, RandomPolicy, first, make_policy,
)


def test_random_policy_is_reproducible_from_its_seed():
    def run(seed):
        tr = MemoryTracer()
        engine("Broadcast").run(RandomPolicy(seed), limit=40, tracer=tr)
        return tr.labels
    assert run(7) == run(7)
    assert len(set(run(7))) > 2


def test_api_hook_policy_and_stop():
    e = engine("Dining", "Table3()")
    seen = []

    def policy(state, enabled):
        seen.append([i.label for i in enabled])
        return enabled[-1] if len(seen) < 3 else None
    summary = e.run(policy)
    assert summary.outcome == "stopped" and summary.steps == 2
    assert seen == [["eat0", "eat1", "eat2"], ["done2"], ["eat0", "eat1", "eat2"]]


def test_limit_zero_and_deadlock_summary():
    e = engine("Chain")
    assert e.run(first, limit=0).line() == "0 steps, step limit reached"
    summary = e.run(first)
    assert summary.line() == "2 steps, deadlock (no enabled interaction)"
    assert e.describe_state(summary.state) == {"ch": {"places": ["d"], "data": {"x": 3, "y": 9}}}


def test_jsonl_trace(tmp_path):
    path = tmp_path / "t.jsonl"
    e = engine("Broadcast")
    e.run(first, limit=2, tracer=JsonlTracer(path))
    recs = [json.loads(line) for line in path.read_text().splitlines()]
    assert recs[0]["initial"]["snd"] == {"places": ["s"], "data": {"v": 0}}
    assert recs[1] == {"step": 1, "enabled": ["bc"], "chosen": "bc", "index": recs[1]["index"],
                       "ports": ["snd.snd", "r1.rcv", "r2.rcv", "r3.rcv"],
                       "values": {"snd.snd": {"v": 0}, "r1.rcv": {"v": 0}, "r2.rcv": {"v": 0}, "r3.rcv": {"v": 0}}}
    assert recs[2]["chosen"] == "bc[snd.snd]" and recs[2]["values"] == {"snd.snd": {"v": 1}}
    assert recs[2]["enabled"] == ["bc[snd.snd]", "r1.work", "r2.work", "r3.work"]
    assert recs[3]["summary"]["outcome"] == "limit" and recs[3]["summary"]["steps"] == 2
    assert recs[3]["summary"]["state"]["snd"]["data"] == {"v": 2}


def test_console_trace_and_deadlock_state():
    out = io.StringIO()
    e = engine("Hierarchy")
    e.run(first, tracer=MultiTracer(ConsoleTracer(out), MemoryTracer()))
    text = out.getvalue().splitlines()
    # the two alternatives' labels would pass 120 columns: they are counted (--trace FILE lists them)
    assert text[0] == ("[    1] Mod.Pass:take[src.a.out,sink.take]  m.src.a.out(v=1); m.sink.take(v=1)    "
                       "(1 of 2 enabled)")
    assert text[1] == "[    2] m.sink.reset"
    assert text[-4:] == ["deadlock state:", "  m.src.a: e v=1", "  m.src.b: e v=2", "  m.sink: w got=2"]


def test_interactive_policy_reads_numbers_state_and_eof():
    e = engine("Dining", "Table3()")
    out = io.StringIO()
    policy = InteractivePolicy(e.format_state, io.StringIO("7\ns\n2\n\n"), out)
    summary = e.run(policy)
    assert summary.outcome == "stopped" and summary.steps == 2      # eat1, then done1 (empty line: first)
    text = out.getvalue()
    assert "[2] eat1" in text and "not a choice: '7'" in text and "p0: think meals=0" in text


def test_make_policy_names():
    assert make_policy("first") is first
    assert isinstance(make_policy("random", 3), RandomPolicy)


def test_generated_source_is_readable_and_kept():
    e = engine("Broadcast")
    src = e.source
    assert "def enabled(s):" in src and "def initial():" in src
    assert "# connector bc: Bcast3(snd.snd, r1.rcv, r2.rcv, r3.rcv)" in src
    assert "# atom r1 (Recv): ready=1, busy=2" in src
    compile(src, "<check>", "exec")
    assert e.code.co_filename.startswith("<bip step")


def test_successors_reach_the_whole_state_space():
    e = engine("Dining", "Table3()")
    seen = {e.initial_state()}
    frontier = list(seen)
    edges = 0
    while frontier:
        nxt = []
        for s in frontier:
            for inter, t in e.successors(s):
                edges += 1
                if t not in seen:
                    seen.add(t)
                    nxt.append(t)
        frontier = nxt
        if len(seen) > 10_000:
            break
    # the meal counters make it infinite: check the control part instead
    control = {tuple(x for k, x in enumerate(s) if k not in (1, 3, 5)) for s in seen}
    assert len(control) == 4        # everyone thinking, or exactly one of three eating
