"""The same structure the pictures draw, as text: data flow, interruptions, constraints and rules."""
from __future__ import annotations

from runtime.pictures.structure import Structure


def outline(s: Structure) -> list[str]:
    """Lines under four headings; a heading with nothing under it is left out."""
    sections: dict[str, list[str]] = {"data flow": [], "interruptions": [], "constraints": [], "rules": []}
    for f in s.flows:
        sections["data flow"].append(f"{f.module}.{f.poster} -> {f.reader}" +
                                     (f" (read by {', '.join(f.codels)})" if f.codels else ""))
    for link in s.links:
        if link.kind == "interrupts" and "abort" in link.ports:
            line = f"{s.owner_of(link.tail)} interrupts {s.owner_of(link.head)}"
            heading = "interruptions"
        elif link.kind in ("constraint", "rule"):
            why = ", ".join(link.rules) or link.label
            line = f"{s.owner_of(link.head)} guarded by the status of {s.owner_of(link.tail)} ({why})"
            heading = "constraints" if link.kind == "constraint" else "rules"
        else:
            continue
        if line not in sections[heading]:
            sections[heading].append(line)
    out: list[str] = []
    for heading, lines in sections.items():
        if lines:
            out.append(f"{heading} ({len(lines)}):")
            out += [f"  {line}" for line in lines]
    return out
