"""What a campaign can vary over: one entry per kind of axis, each turning a value of the file into model parameters.

An axis is written ``KIND`` or ``KIND.NAME`` under ``vary:`` with a list of
values (``define.PERIOD: [10, 15]``, ``wcet-scale: [0.5, 1, 2]``,
``period.NDD.motion: [50 ms, 100 ms]``).  A new kind of axis (the platform's
cores or policy) is one more :class:`AxisKind` in :data:`AXES`: how it reads
a value and which model parameter it sets.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, replace
from typing import Any, Callable

from genom2bip.campaign.params import ModelParams


@dataclass(frozen=True)
class AxisKind:
    """A kind of axis: ``read(text, value)`` gives the value or raises ValueError with what was expected;
    ``apply(params, name, value)`` gives the model parameters of that point."""

    name: str
    help: str
    read: Callable[[Any], Any]
    apply: Callable[[ModelParams, str, Any], ModelParams]
    named: bool = False  # written KIND.NAME (a define's macro, a task's Module.task)
    timed: bool = False  # changes only a timed model
    unit: str = ""  # the unit of a numeric value in pictures
    path: bool = False  # a file, relative to the campaign file (the reader makes it absolute)


def _number(value: Any) -> float | int:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError("a number expected")
    return value


def _factor(value: Any) -> float | int:
    value = _number(value)
    from genom2bip.variants import MAX_WCET_SCALE

    if not 0 <= value <= MAX_WCET_SCALE:  # NaN too
        raise ValueError(f"a factor from 0 to {MAX_WCET_SCALE} expected")
    return value


def _duration_us(value: Any) -> int:
    """``10 ms``, ``1.5 s``, ``500 us`` as µs (ValueError otherwise)."""
    from genom2bip.observers import parse_duration

    us = parse_duration(str(value)) if isinstance(value, str) else None
    if us is None:
        raise ValueError("a duration expected (e.g. 10 ms, 1 s, 500 us)")
    return us


def _positive_duration(value: Any) -> int:
    us = _duration_us(value)
    if us <= 0:
        raise ValueError("a positive duration expected")
    return us


def _cores(value: Any) -> int:
    from genom2bip.platform import MAX_CORES

    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= MAX_CORES:
        raise ValueError(f"a whole number of cores from 1 to {MAX_CORES} expected")
    return value


def _policy(value: Any) -> str:
    from genom2bip.platform import POLICIES

    if value not in POLICIES:
        raise ValueError(f"a policy expected ({' or '.join(POLICIES)})")
    return value


def _file(value: Any) -> str:
    """A platform file's path as written; the campaign file's reader makes it absolute and checks it is there."""
    if not isinstance(value, str) or not value:
        raise ValueError("a platform file's path expected")
    return value


def _define(value: Any) -> str | int | float:
    if isinstance(value, (dict, list)) or value is None:
        raise ValueError("a macro value expected (a number or a word)")
    if isinstance(value, bool):
        return int(value)
    return value


def _set_define(params: ModelParams, name: str, value: Any) -> ModelParams:
    return replace(params, defines=tuple(sorted({**dict(params.defines), name: str(value)}.items())))


def _set_period(params: ModelParams, name: str, us: int) -> ModelParams:
    return replace(params, periods=tuple(sorted({**dict(params.periods), name: us}.items())))


#: Every kind of axis, by the name written in the file.
AXES: dict[str, AxisKind] = {a.name: a for a in (
    AxisKind("define", "a preprocessor macro (define.NAME: values), as -D NAME=VALUE", _define, _set_define,
             named=True),
    AxisKind("wcet-scale", "every codel's WCET times a factor (the default WCET too)", _factor,
             lambda p, _, v: replace(p, wcet_scale=float(v)), timed=True, unit="×"),
    AxisKind("default-wcet", "the WCET of the codels that declare none (a duration)", _duration_us,
             lambda p, _, v: replace(p, default_wcet_us=v), timed=True, unit="ms"),
    AxisKind("period", "the period of a task (period.Module.task: durations)", _positive_duration, _set_period,
             named=True, timed=True, unit="ms"),
    AxisKind("tick", "the tick's resolution (a duration)", _positive_duration,
             lambda p, _, v: replace(p, tick_us=v), timed=True, unit="ms"),
    AxisKind("platform", "the platform file (paths relative to the campaign file)", _file,
             lambda p, _, v: replace(p, platform=v), timed=True, path=True),
    AxisKind("cores", "the platform's cores (over its file's; without one, that many cores under EDF)", _cores,
             lambda p, _, v: replace(p, cores=v), timed=True),
    AxisKind("policy", "the platform's scheduling policy (edf, fixed-priority; over its file's)", _policy,
             lambda p, _, v: replace(p, policy=v), timed=True),
)}

#: The macro of ``define.NAME`` and the task of ``period.Module.task``.
NAMES = {"define": re.compile(r"[A-Za-z_]\w*\Z"), "period": re.compile(r"[A-Za-z_]\w*\.[A-Za-z_]\w*\Z")}


def axis_kind(key: str) -> tuple[AxisKind, str]:
    """``(kind, name)`` of an axis key; ValueError saying what is expected."""
    kind_name, _, name = key.partition(".")
    kind = AXES.get(kind_name)
    if kind is None:
        known = ", ".join(a.name + (".NAME" if a.named else "") for a in AXES.values())
        raise ValueError(f"unknown axis {key!r} (axes: {known})")
    if kind.named and not NAMES[kind.name].match(name):
        what = "a macro name" if kind.name == "define" else "a task Module.task"
        raise ValueError(f"axis {key!r}: {kind.name}.NAME with {what} expected")
    if not kind.named and name:
        raise ValueError(f"axis {key!r}: {kind.name} takes no name")
    return kind, name


def shown(kind: AxisKind, value: Any) -> float | None:
    """A value as a number on a picture's axis (durations in ms), None when it is not a number."""
    if isinstance(value, bool):
        return None
    if kind.unit == "ms":
        return value / 1000
    if isinstance(value, (int, float)):
        return float(value)
    try:
        return float(value)
    except (TypeError, ValueError):
        return None
