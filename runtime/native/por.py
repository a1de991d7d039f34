"""Static tables of the compiled search's partial-order reduction (strong stubborn sets over interaction sources).

A source (a connector or a lone port: all its interactions and codel
outcomes together) writes the atoms of its ports and reads them; a source
that is low in a compound priority also reads the atoms of the sources high
in the rules its rules reach, and of the data the priority guards name,
since its enabledness depends on them.  Two sources are dependent when one writes
what the other reads or writes.  ``search.c`` builds, in each state, the
closure of one enabled source under: an enabled member adds every source
dependent on it; a disabled member adds a necessary enabling set (the
writers of the atom of one of its ports that is not enabled, for a
rendezvous or a lone port; the writers of everything it reads otherwise).
The enabled members form the ample set.  A source is visible when an
observer's automaton moves on one of its interactions or it writes an atom
the observer's predicate reads; a proper ample set holds no visible source.
"""
from __future__ import annotations

from runtime.props.predicates import atoms_read


def source_atoms(src, flat) -> set[int]:
    if src.kind == "port":
        return {src.port.atom}
    return {flat.ports[p].atom for p in src.leaves}


def _reads_only(fp, flat) -> bool:
    """Whether firing atom port ``fp`` leaves its atom as it was: every transition on it is a self-loop with
    no action (a control atom's status port, which the rules' guards read)."""
    trs = [t for t in flat.atoms[fp.atom].type.transitions if t.port == fp.name]
    return bool(trs) and all(set(t.sources) == set(t.targets) and not t.action and t.resume is None
                             and t.urgency is None for t in trs)


def _down_names(src) -> set[str] | None:
    """The port parameters a connector's down actions mention (None: any of them, for nested connectors)."""
    con = src.connector
    if any(len(param) != 1 or not hasattr(param[0], "port") for param in con.params):
        return None
    text = " ".join(repr(st) for spec in con.type.interactions for st in spec.down)
    return {p.name for p in con.type.params if f"port='{p.name}'" in text}


def written_atoms(src, flat) -> set[int]:
    """Atoms a source may change: those of its ports, less the ports it only reads.

    A port only reads when its transitions are action-less self-loops and the connector's down actions
    do not write its data (an eager internal transition cannot follow: the atom's state is unchanged).
    """
    if src.kind == "port":
        return set() if _reads_only(src.port, flat) else {src.port.atom}
    down = _down_names(src)
    if down is None:
        return source_atoms(src, flat)
    names = {param[0].port: p.name for param, p in zip(src.connector.params, src.connector.type.params)}
    return {flat.ports[q].atom for q in src.leaves
            if not _reads_only(flat.ports[q], flat) or names.get(q) in down or q not in names}


def visible_sources(sources, flat, monitors) -> list[bool]:
    """Sources some observer watches: its automaton moves on one of their interactions, or its predicate's atoms."""
    out = [False] * len(sources)
    for mon, statics in monitors:  # statics list every mask a source's define allows (export.interactions)
        watched = atoms_read(flat, mon.pred)
        for k, st in enumerate(statics):
            if any(q2 != q for q, q2 in mon.delta[k].items()):
                out[st.source.index] = True
        for src in sources:
            if written_atoms(src, flat) & watched:
                out[src.index] = True
    return out


def _bits(n: int, ids) -> int:
    m = 0
    for i in ids:
        m |= 1 << i
    return m


def _row(mask: int, words: int) -> str:
    return "{" + ", ".join(f"UINT64_C({(mask >> (64 * k)) & (2**64 - 1)})" for k in range(words)) + "}"


def _priority_reads(src, sources, writes, flat, prio) -> int:
    """Atoms (bit mask) whose state decides whether compound priorities block ``src``.

    ``src`` is blocked when a rule it is low in reaches (through the rules' order, every guard assumed
    true: a superset of what any combination of guards reaches) a rule whose high side is enabled; the
    guards themselves read the atoms of the data they name.
    """
    if prio is None or src.connector is None:
        return 0
    cid = src.connector.id
    mine = [i for i, rule in enumerate(prio.rules) if any(c == cid for c, _ in rule[1])]
    if not mine:
        return 0
    seen, stack = set(mine), list(mine)
    while stack:
        for y in prio.edges[stack.pop()]:
            if y not in seen:
                seen.add(y)
                stack.append(y)
    high = {c for r in seen for c, _ in prio.rules[r][2]}
    out = 0
    for s in sources:
        if s.connector is not None and s.connector.id in high:
            out |= writes[s.index]
    owner = {}
    for fa in flat.atoms:
        for slot in range(fa.offset, fa.offset + 1 + len(fa.variables)):
            owner[slot] = fa.index
    for r, _ in prio.guards:
        for slot, _ty in flat.priorities[r].data.values():
            out |= 1 << owner[slot] if slot in owner else (1 << len(flat.atoms)) - 1
    return out


def gen_por(w, sources, flat, prio, monitors, enabled: bool) -> None:
    """The tables search.c's ``ample`` reads: DEP, NESALL, WRITERS, the rendezvous ports, VISIBLE; POR_ON."""
    n, na = len(sources), len(flat.atoms)
    words = max((n + 63) // 64, 1)
    w(f"#define POR_ON {1 if enabled else 0}")
    w(f"#define SW {words}")
    w(f"#define NATOMS {max(na, 1)}")
    writes = [_bits(na, written_atoms(s, flat)) for s in sources]
    reads = [_bits(na, source_atoms(s, flat)) | _priority_reads(s, sources, writes, flat, prio) for s in sources]
    writers = [0] * na
    readers = [0] * na
    for s in sources:
        for a in range(na):
            if writes[s.index] >> a & 1:
                writers[a] |= 1 << s.index
            if reads[s.index] >> a & 1:
                readers[a] |= 1 << s.index
    dep, nes = [], []
    for s in sources:
        d, e = 1 << s.index, 0
        for a in range(na):
            if writes[s.index] >> a & 1:
                d |= readers[a] | writers[a]
            if reads[s.index] >> a & 1:
                d |= writers[a]
                e |= writers[a]
        dep.append(d)
        nes.append(e)
    w(f"static const uint64_t DEP[NSRC][SW] = {{{', '.join(_row(d, words) for d in dep)}}};")
    w(f"static const uint64_t NESALL[NSRC][SW] = {{{', '.join(_row(e, words) for e in nes)}}};")
    rows = ', '.join(_row(x, words) for x in writers) or _row(0, words)
    w(f"static const uint64_t WRITERS[NATOMS][SW] = {{{rows}}};")
    off, ports, atoms = [0], [], []
    for s in sources:
        if s.kind == "port":
            ports.append(s.port.id)
            atoms.append(s.port.atom)
        elif s.kind == "rendezvous":
            for p in s.leaves:
                ports.append(p)
                atoms.append(flat.ports[p].atom)
        off.append(len(ports))
    w(f"static const int RZOFF[NSRC + 1] = {{{', '.join(map(str, off))}}};")
    w(f"static const int RZPORT[] = {{{', '.join(map(str, ports)) or '0'}}};")
    w(f"static const int RZATOM[] = {{{', '.join(map(str, atoms)) or '0'}}};")
    vis = visible_sources(sources, flat, monitors)
    w(f"static const uint8_t VISIBLE[NSRC] = {{{', '.join('1' if v else '0' for v in vis)}}};")
