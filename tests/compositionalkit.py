"""Random small BIP models for the soundness properties of the compositional analysis (hypothesis)."""
from __future__ import annotations

from hypothesis import strategies as st


@st.composite
def models(draw) -> str:
    """A package ``R`` with root ``Top()``: 2-4 atoms with a bool flag, rendezvous and broadcast connectors,
    guards on the flag (through ports and in atoms), a ``down`` that writes a flag, internal transitions,
    compound and atom priorities, an unbounded counter read by a guard, lone ports."""
    n_atoms = draw(st.integers(2, 4))
    atoms, ports_of = [], []
    for a in range(n_atoms):
        n_places = draw(st.integers(2, 4))
        n_ports = draw(st.integers(1, 3))
        lines = [f"  atom type A{a}()", "    data bool f", "    data int c"]
        lines += [f"    export port Flag p{k}(f)" for k in range(n_ports)]
        lone = draw(st.booleans())
        if lone:
            lines.append("    port Flag q(f)")
        places = [f"S{k}" for k in range(n_places)]
        lines.append(f"    place {', '.join(places)}")
        lines.append(f"    initial to S0 do {{ f = {draw(st.sampled_from(['true', 'false']))}; c = 0; }}")
        used = set()
        for k in range(draw(st.integers(1, 6))):
            port = draw(st.integers(0, n_ports - 1))
            src = draw(st.integers(0, n_places - 1))
            if (port, src) in used:
                continue
            used.add((port, src))
            dst = draw(st.integers(0, n_places - 1))
            guard = draw(st.sampled_from(["", " provided (f)", " provided (!f)", " provided (c < 2)"]))
            action = draw(st.sampled_from(["", " do { f = !f; }", " do { c = c + 1; }", " do { f = true; }"]))
            lines.append(f"    on p{port} from {places[src]} to {places[dst]}{guard}{action}")
        if lone:
            src = draw(st.integers(0, n_places - 1))
            lines.append(f"    on q from {places[src]} to {places[draw(st.integers(0, n_places - 1))]}"
                         f" provided (c < 3) do {{ c = c + 1; }}")
        if n_ports >= 2 and draw(st.integers(0, 3)) == 0:  # an atom priority, low index below high: no cycle
            lo = draw(st.integers(0, n_ports - 2))
            lines_priority = f"    priority ap p{lo} < p{draw(st.integers(lo + 1, n_ports - 1))}"
        else:
            lines_priority = ""
        if draw(st.booleans()):
            src = draw(st.integers(0, n_places - 2))
            dst = draw(st.integers(src + 1, n_places - 1))  # forward only: no livelock
            lines.append(f"    internal from {places[src]} to {places[dst]} provided (f)")
        if lines_priority:
            lines.append(lines_priority)
        lines.append("  end")
        atoms.append("\n".join(lines))
        ports_of.append(n_ports)
    conns, prios = [], []
    n_conns = draw(st.integers(1, 5))
    all_ports = [(a, k) for a in range(n_atoms) for k in range(ports_of[a])]
    for c in range(n_conns):
        size = draw(st.integers(1, min(3, n_atoms)))
        chosen_atoms = draw(st.lists(st.integers(0, n_atoms - 1), min_size=size, max_size=size, unique=True))
        ends = [f"a{a}.p{draw(st.integers(0, ports_of[a] - 1))}" for a in chosen_atoms]
        kind = draw(st.sampled_from(["R", "G", "B", "W"])) if size >= 2 else "R"
        conns.append(f"    connector {kind}{size} k{c}({', '.join(ends)})")
    for c in range(n_conns):
        if c > 0 and draw(st.integers(0, 3)) == 0:
            low = draw(st.integers(0, c - 1))
            prios.append(f"    priority r{c} k{low}:* < k{c}:*")
    del all_ports
    types = []
    for size in (1, 2, 3):
        params = ", ".join(f"Flag x{i}" for i in range(size))
        names = " ".join(f"x{i}" for i in range(size))
        types.append(f"  connector type R{size}({params})\n    define {names}\n  end")
        if size >= 2:
            types.append(f"  connector type G{size}({params})\n    define {names}\n"
                         f"    on {names} provided (x0.b == x1.b)\n  end")
            trig = "x0' " + " ".join(f"x{i}" for i in range(1, size))
            types.append(f"  connector type B{size}({params})\n    define {trig}\n  end")
            types.append(f"  connector type W{size}({params})\n    define {names}\n"
                         f"    on {names} down {{ x1.b = !x0.b; }}\n  end")
    comps = "\n".join(f"    component A{a} a{a}()" for a in range(n_atoms))
    return ("package R\n  port type Flag(bool b)\n" + "\n".join(atoms) + "\n" + "\n".join(types) +
            "\n  compound type Top()\n" + comps + "\n" + "\n".join(conns) + "\n" + "\n".join(prios) + "\n  end\nend\n")
