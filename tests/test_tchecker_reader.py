"""TChecker files read into the zone engine's model: verdicts known by hand, and every refusal located.

The fixtures (tests/fixtures/tchecker/) are small models written for these tests in TChecker's format; each
says in its comment why its verdicts are what they are.
"""
from fractions import Fraction
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from runtime.cli import main
from runtime.tchecker.reach import configurations, reach

FIXTURES = Path(__file__).parent / "fixtures" / "tchecker"


def run(capsys, *argv):
    code = main(["reach", *map(str, argv)])
    out, err = capsys.readouterr()
    return code, out, err


# -- verdicts -------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("grid", [1, 2, 3])
def test_fischer_keeps_mutual_exclusion_on_every_grid(capsys, grid):
    code, out, err = run(capsys, FIXTURES / "fischer2.tck", "--labels", "cs1,cs2", "--grid", grid)
    assert code == 0, err
    assert f"verdict: unreachable (on the 1/{grid} time grid: the model has strict clock constraints)" in out
    assert "trace:" not in out


@pytest.mark.parametrize("grid,wait", [(1, Fraction(3)), (2, Fraction(5, 2)), (4, Fraction(9, 4))])
def test_fischer_enters_cs_strictly_after_k_with_a_replayed_trace(grid, wait):
    r = reach(FIXTURES / "fischer2.tck", ["cs1"], grid)
    assert (r.verdict, r.exact) == ("reachable", True)
    # the shortest way: request, write id at once, then wait more than K = 2: the first grid point past 2
    assert [step for _, step in r.trace] == ["P1@tau(A->req)", "P1@tau(req->wait)", "P1@tau(wait->cs)"]
    assert [delay for delay, _ in r.trace] == [0, 0, wait]


def test_a_coarse_grid_can_miss_what_dense_time_reaches_and_says_so(capsys):
    # grid.tck: reachable in dense time (tck-reach agrees), with delays of 1/3; a grid of 1/2 misses it
    path = FIXTURES / "grid.tck"
    for grid in (1, 2):
        code, out, _ = run(capsys, path, "-l", "done", "--grid", grid)
        assert code == 0
        assert f"verdict: unreachable (on the 1/{grid} time grid: the model has strict clock constraints)" in out
    r = reach(path, ["done"], 3)
    assert r.verdict == "reachable" and r.exact
    assert [d for d, _ in r.trace] == [Fraction(1, 3), Fraction(1, 3)]


def test_fischer_configurations_are_tcheckers(tmp_path):
    # what tck-reach -C graph lists for this file: 18 configurations; never both in cs, never cs with id == 0
    got = configurations(FIXTURES / "fischer2.tck", 2)
    assert len(got) == 18
    assert not any(locs == ("cs", "cs") for locs, _ in got)
    assert all(dict(ints)["id"] == 1 for locs, ints in got if locs[0] == "cs")
    assert ((("wait", "cs"), (("id", 2),))) in got


def test_fischer_with_a_non_strict_wait_loses_mutual_exclusion(capsys):
    # no strict constraint: no grid needed and the verdict is dense time's
    code, out, err = run(capsys, FIXTURES / "fischer2_nonstrict.tck", "--labels", "cs1,cs2")
    assert code == 4, err  # found (runtime/exits.py)
    assert "verdict: reachable\n" in out
    trace = out.split("trace:\n", 1)[1].splitlines()
    assert sum("(wait->cs)" in line for line in trace) == 2
    assert all(line.startswith("  delay ") for line in trace)


def test_a_committed_location_hides_the_window_between_two_writes(tmp_path):
    path = FIXTURES / "committed_window.tck"
    assert reach(path, ["seen"]).verdict == "unreachable"
    assert configurations(path) == {(("l0", "m0"), (("flag", 0),)), (("l1", "m0"), (("flag", 1),)),
                                    (("l2", "m0"), (("flag", 0),))}
    plain = tmp_path / "plain.tck"
    plain.write_text(path.read_text().replace("{committed:}", "{}"))
    assert reach(plain, ["seen"]).verdict == "reachable"
    assert len(configurations(plain)) == 5  # B may read flag == 1: (l1, m1) and then (l2, m1)


def test_a_committed_location_with_no_way_out_stops_every_other_process(tmp_path):
    # TChecker's semantics: a transition must involve a committed process when there is one, enabled or not
    path = FIXTURES / "committed_blocks.tck"
    assert reach(path, ["moved"]).verdict == "unreachable"
    assert configurations(path) == {(("l0", "m0"), (("flag", 0),))}
    plain = tmp_path / "plain.tck"
    plain.write_text(path.read_text().replace("{initial: : committed:}", "{initial:}"))
    assert reach(plain, ["moved"]).verdict == "reachable"


def test_time_does_not_pass_in_an_urgent_location(tmp_path):
    path = FIXTURES / "urgent.tck"
    assert reach(path, ["late"]).verdict == "unreachable"
    assert reach(path, ["now"]).verdict == "reachable"
    r = reach(path, ["qlate"])
    assert r.verdict == "reachable"
    steps = [s for _, s in r.trace]
    assert steps.index("P@b(l0->now)") < steps.index("Q@c(q0->q1)")  # Q's clock grows only once P left l0
    assert sum(d for d, _ in r.trace) == 1
    assert configurations(path) == {(("l0", "q0"), ()), (("now", "q0"), ()), (("now", "q1"), ())}
    plain = tmp_path / "plain.tck"
    plain.write_text(path.read_text().replace("{initial: : urgent:}", "{initial:}"))
    late = reach(plain, ["late"])
    assert late.verdict == "reachable" and late.trace == [(1, "P@a(l0->late)")]


def test_a_sync_vector_moves_its_processes_together_and_only_together():
    path = FIXTURES / "sync.tck"
    r = reach(path, ["p1done"])
    assert r.verdict == "reachable"
    assert [s for _, s in r.trace] == ["P2@b(m0->m1)", "P1@a(l0->l1),P2@a(m1->m2)"]
    assert reach(path, ["never"]).verdict == "unreachable"  # x >= 3 and y <= 2 at one instant, x == y
    assert {locs for locs, _ in configurations(path)} == {("l0", "m0", "s0", "t0"), ("l0", "m1", "s0", "t0"),
                                                          ("l1", "m2", "s0", "t0")}


def test_a_sync_runs_its_statements_in_the_order_it_lists_the_processes(tmp_path):
    path = tmp_path / "order.tck"
    path.write_text("system:order\nevent:a\nint:1:0:2:0:n\n"
                    "process:P1\nlocation:P1:l0{initial:}\nlocation:P1:l1{}\nedge:P1:l0:l1:a{do:n=1}\n"
                    "process:P2\nlocation:P2:m0{initial:}\nlocation:P2:m1{}\nedge:P2:m0:m1:a{do:n=2}\n"
                    "sync:P2@a:P1@a\n")
    assert configurations(path) == {(("l0", "m0"), (("n", 0),)), (("l1", "m1"), (("n", 1),))}


def test_an_integer_no_edge_touches_keeps_its_initial_value(tmp_path):
    path = tmp_path / "still.tck"
    path.write_text("system:still\nevent:a\nint:1:0:3:2:k\nprocess:P\nlocation:P:l0{initial:}\n"
                    "location:P:l1{}\nedge:P:l0:l1:a\n")
    assert configurations(path) == {(("l0",), (("k", 2),)), (("l1",), (("k", 2),))}


def test_a_weak_constraint_takes_part_wherever_its_process_has_an_edge_of_the_event():
    path = FIXTURES / "weak.tck"
    assert reach(path, ["moved"]).verdict == "unreachable"  # Q must go along, and its target forbids x >= 3
    r = reach(path, ["early"])
    assert r.verdict == "reachable" and r.trace == [(0, "P@c(l0->l2),Q@c(q0->q2)")]
    assert configurations(path) == {(("l0", "q0", "r0"), ()), (("l2", "q2", "r0"), ())}
    # were R's absence ignored (R must not block), or Q free to stay out, moved would be reachable


def test_an_assignment_out_of_its_domain_disables_the_edge():
    path = FIXTURES / "bounded.tck"
    assert reach(path, ["one"]).verdict == "reachable"
    assert reach(path, ["two"]).verdict == "unreachable"
    assert configurations(path) == {(("n0",), (("n", 0), ("a[0]", 0), ("a[1]", 0))),
                                    (("n1",), (("n", 1), ("a[0]", 0), ("a[1]", 3)))}


def test_figures_exit_statuses_and_limits(capsys):
    code, out, err = run(capsys, FIXTURES / "fischer2.tck", "--grid", "1")
    assert code == 0
    assert "labels: none (the whole zone graph is explored)" in out
    for line in ("stored states: ", "visited transitions: ", "time: ", "memory: "):
        assert line in out
    code, out, _ = run(capsys, FIXTURES / "fischer2.tck", "-l", "cs1,cs2", "--grid", "1", "--max-states", "3")
    assert code == 5  # inconclusive
    assert "verdict: unknown (stopped at the state limit)" in out
    code, out, err = run(capsys, FIXTURES / "sync.tck", "-l", "p1done,nowhere")
    assert code == 0
    assert "no location carries label(s) nowhere" in err


# -- refusals -------------------------------------------------------------------------------------------------

HEAD = "system:s\nevent:a\nprocess:P\nclock:1:x\nlocation:P:l0{initial:}\nlocation:P:l1{}\n"

BAD = [
    ("unknown process in a sync", HEAD + "process:R\nlocation:R:r{initial:}\nsync:P@a:Q@a\n",
     9, 10, "unknown process 'Q'"),
    ("bad syntax in a guard", HEAD + "edge:P:l0:l1:a{provided: x <= }\n", 7, 30,
     "bad provided: unexpected the end of the value"),
    ("a character outside the format", HEAD + "edge:P:l0:l1:a{provided: x <= 2 $ 3}\n", 7, 33,
     "bad provided: unexpected '$'"),
    ("an unknown declaration", HEAD + "proces:Q\n", 7, 1, "unknown declaration 'proces'"),
    ("a keyword as a name", HEAD.replace("system:s", "system:sync"), 1, 8, "'sync' is a keyword, not a name"),
    ("an unknown variable", HEAD + "edge:P:l0:l1:a{provided: z == 1}\n", 7, 26, "unknown variable 'z'"),
    ("a guard on a weakly synchronised edge", HEAD + "process:R\nlocation:R:r{initial:}\n"
     "edge:R:r:r:a{provided: x <= 1}\nsync:P@a:R@a?\n", 9, 14,
     "a guard on an edge of R's weakly synchronised event 'a'"),
    ("a diagonal constraint", HEAD + "clock:1:y\nedge:P:l0:l1:a{provided: x - y <= 1}\n", 8, 26,
     "unsupported: diagonal clock constraint"),
    ("a clock of two processes", HEAD + "edge:P:l0:l1:a{provided: x <= 1}\nprocess:R\nlocation:R:r{initial:}\n"
     "edge:R:r:r:a{do: x = 0}\n", 10, 18,
     "unsupported: clock x is used by processes"),
    ("a while statement", HEAD + "int:1:0:3:0:n\nedge:P:l0:l1:a{do: while n < 3 do n = n + 1 end}\n", 8, 20,
     "unsupported: 'while' statements"),
    ("a clock compared with a variable", HEAD + "int:1:0:3:0:n\nedge:P:l0:l1:a{provided: x <= n}\n", 8, 31,
     "unsupported: 'n' as the bound of clock x: expected a constant"),
    ("an invariant on an integer", HEAD + "int:1:0:3:0:n\nlocation:P:l2{invariant: n < 2}\n", 8, 26,
     "unsupported: an invariant on integer variables"),
    ("two initial locations", HEAD.replace("l1{}", "l1{initial:}"), 6, 12,
     "process P has several initial locations"),
    ("a strict constraint without a grid", HEAD + "edge:P:l0:l1:a{provided: x < 2}\n", 7, 26,
     "strict clock constraint: the zone engine's bounds are integers"),
    ("a division", HEAD + "int:1:0:3:0:n\nedge:P:l0:l1:a{do: n = n / 2}\n", 8, 24, "unsupported operator '/'"),
    ("a negative clock", HEAD + "edge:P:l0:l1:a{do: x = -1}\n", 7, 24, "clock x set to -1: clocks are never negative"),
    ("an unknown location", HEAD + "edge:P:l0:l9:a\n", 7, 11, "unknown location 'l9' of process P"),
]


@pytest.mark.parametrize("text,line,column,message", [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_each_refusal_names_its_place_and_explores_nothing(capsys, tmp_path, text, line, column, message):
    path = tmp_path / "bad.tck"
    path.write_text(text)
    before = sorted(tmp_path.iterdir())
    code, out, err = run(capsys, path)
    assert code == 1
    assert out == ""  # no verdict, no figures: nothing was explored
    first, quoted, caret = err.splitlines()[:3]
    assert first.startswith(f"{path}:{line}:{column}: error: {message}"), err
    assert quoted.strip() == text.splitlines()[line - 1].strip()
    assert caret.index("^") - quoted.index(quoted.strip()) == column - 1
    assert sorted(tmp_path.iterdir()) == before  # nothing written beside the file


def test_a_missing_or_binary_file_is_an_input_error(capsys, tmp_path):
    code, out, err = run(capsys, tmp_path / "none.tck")
    assert (code, out) == (1, "")
    assert err.startswith(f"{tmp_path / 'none.tck'}: error: cannot read the TChecker file")
    binary = tmp_path / "b.tck"
    binary.write_bytes(b"system:s\n\xff\xfe\n")
    code, out, err = run(capsys, binary)
    assert (code, out) == (1, "")
    assert err.startswith(f"{binary}:2:1: error: not a UTF-8 text file")


# -- malformed input never escapes as a traceback ------------------------------------------------------------

_PIECES = ["system:s\n", "process:P\n", "event:a\n", "clock:1:x\n", "int:1:0:3:0:n\n", "location:P:l0{initial:}\n",
           "location:P:l1{invariant: x <= 2}\n", "edge:P:l0:l1:a{provided: x > 1 && n == 0 : do: n = n + 1; x = 0}\n",
           "sync:P@a:P@a\n", "{", "}", ":", "@", "?", "#", "\n", " ", "x", "<=", "&&", "(", ")", "[", "]", "-", "1",
           "committed:", "urgent:", "labels:", "do:", "provided:", "=", ";", "!", "\t", "é", "\r\n",
           "int:0:5:1:9:m\n", "clock:0:y\n", "clock:2:z\n", "edge:P:l0:l0:a{do: z[1] = 0; z[n] = 1}\n",
           "location:P:l2{urgent: : committed:}\n", "edge:P:l1:l2:a{provided: x - x < 1}\n", "n", "z[2]", "a", "P",
           "edge:P:l1:l0:a{provided: n}\n", "edge:P:l1:l0:a{do: n = 9}\n", "location:P:l3{invariant: n}\n"]
_HEAD = "system:s\nevent:a\nprocess:P\nclock:1:x\nint:1:0:3:0:n\n"


@given(st.booleans(), st.lists(st.sampled_from(_PIECES), max_size=30))
@settings(max_examples=300, deadline=None, derandomize=True)
def test_any_text_is_read_or_refused_with_a_located_error(tmp_path_factory, head, pieces):
    from runtime.diagnostics import DiagnosticError
    from runtime.tchecker.reach import load

    path = tmp_path_factory.mktemp("fuzz") / "f.tck"
    path.write_text((_HEAD if head else "") + "".join(pieces), encoding="utf-8")
    try:
        load(path, 2)
    except DiagnosticError as e:
        assert all(d.span.file == str(path) for d in e.diagnostics)
        assert e.render().startswith(str(path))


@pytest.mark.parametrize("name", ["fischer2.tck", "fischer2_nonstrict.tck", "committed_window.tck", "urgent.tck"])
def test_local_lu_bounds_change_no_verdict_and_no_configuration(name):
    # Extra_LU with each place's bounds (ZoneExplorer's local_ceilings) forgets more of a zone; what is reachable
    # must not change, in the C search as in the Python one.
    from runtime.tchecker.reach import load
    from runtime.zones.search import ZoneExplorer

    _, tr = load(FIXTURES / name, 2)
    seen = set()
    for engine in ("python", "c"):
        for local in (False, True):
            z = ZoneExplorer(tr.package, tr.root, engine=engine, local_ceilings=local)
            result = z.explore()
            assert result.complete
            seen.add(frozenset(n.state for n in z.nodes))
    assert len(seen) == 1


@pytest.mark.parametrize("name", ["fischer2.tck", "fischer2_nonstrict.tck", "philosophers2.tck"])
def test_no_zone_is_stored_that_a_later_one_covers(name):
    # Each zone is stored under one matrix (extrapolation puts a raised lower bound back to x >= 0), and a clock
    # idle at a state keeps no bound at all (minus infinity on both sides, as TChecker's ExtraLU+): the search
    # then never stores a zone that one reached later covers.  tck-reach -a covreach visits 18, 28 and 11 nodes on
    # these files and covers none it stored; we stored 22, 32 and 14.
    r = reach(FIXTURES / name, [], 2)
    assert r.verdict == "unreachable"
    assert r.states == r.kept
    assert r.kept == {"fischer2.tck": 18, "fischer2_nonstrict.tck": 28, "philosophers2.tck": 11}[name]


def test_two_philosophers_never_eat_at_once():
    # philosophers2.tck: each eats holding both forks; tck-reach says unreachable too
    assert reach(FIXTURES / "philosophers2.tck", ["eating1", "eating2"]).verdict == "unreachable"
    assert reach(FIXTURES / "philosophers2.tck", ["eating2"]).verdict == "reachable"


@pytest.mark.parametrize("name", ["fischer2.tck", "fischer2_nonstrict.tck", "committed_window.tck", "urgent.tck",
                                  "sync.tck", "weak.tck"])
def test_points_past_an_invariant_are_no_state_and_change_nothing_reachable(name):
    # With invariants part of the state (ZoneExplorer's invariants, as reach runs), the points extrapolation keeps
    # past a place's invariant are not stored as a piece where time cannot pass: fewer steps, the same
    # configurations and the same zones kept; the C search stores what the Python one does.
    from runtime.tchecker.reach import explorer, load

    _, tr = load(FIXTURES / name, 2)
    runs = {}
    for engine in ("python", "c"):
        for hard in (False, True):
            z = explorer(tr, invariants=hard, engine=engine)
            result = z.explore()
            assert result.complete
            kept = sorted((n.state, n.zone.tobytes()) for n in z.nodes if not n.covered)
            steps = sum(len(out) for out in z.out)
            nodes = [(n.state, n.parent, n.via, n.covered, n.by, None if n.stored is None else n.stored.tobytes())
                     for n in z.nodes]
            runs[engine, hard] = (frozenset(n.state for n in z.nodes), kept, steps, nodes)
    assert runs["python", True] == runs["c", True] and runs["python", False] == runs["c", False]
    assert runs["c", True][:2] == runs["c", False][:2]
    assert runs["c", True][2] <= runs["c", False][2]


def test_fischer_stores_no_piece_past_an_invariant():
    # Fischer 2: in req (x <= 2) a clock no guard ahead reads from below loses its upper bound to extrapolation;
    # the successors of such a zone were cut in two, the piece past x <= 2 stored and then covered.
    from runtime.tchecker.reach import explorer, load

    _, tr = load(FIXTURES / "fischer2.tck", 2)
    counts = []
    for hard in (False, True):
        z = explorer(tr, invariants=hard)
        z.explore()
        counts.append(len(z.search.steps))
    assert counts[1] < counts[0]
