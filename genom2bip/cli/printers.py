"""Traces, states and progress as ``verify`` and its engines print them."""
from __future__ import annotations


def print_trace(steps, indent: str = "    ", sources: dict[str, str] | None = None) -> None:
    """One line per step; with ``sources`` (:func:`step_sources`), each names the description line it comes from."""
    if not steps:
        print(f"{indent}(the initial state)")
    where = sources or {}
    for n, step in enumerate(steps, 1):
        source = where.get(getattr(step, "label", str(step)))
        print(f"{indent}{n:4d}  {step}" + (f"    ({source})" if source else ""))


def step_sources(flat) -> dict[str, str]:
    """Interaction label -> ``file:line:column`` of the service, codel or task it models (``@source``)."""
    from runtime.model import source_of

    out: dict[str, str] = {}
    for fc in flat.connectors:
        source = source_of(fc.instance.annotations)
        if source and fc.label not in out:
            out[fc.label] = source
    return out


def print_state(engine, state, indent: str = "    ") -> None:
    for line in engine.format_state(state).splitlines():
        print(f"{indent}{line}")


def progress(args):
    """The progress line of a search, as ``--progress`` / ``--quiet`` ask."""
    from runtime.explore import Progress
    return Progress(force=args.progress, enabled=not args.quiet)
