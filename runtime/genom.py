"""What Python codels use: :class:`Ref` holders for ``out``/``inout`` arguments and :class:`Throw` for exceptions.

A codel is a plain function called with keyword arguments (docs/runtime.md)::

    from runtime.genom import Throw

    def nddCheckSpeed(max_speed):
        if max_speed["v"] <= 0:
            raise Throw("e_bad_params", value=max_speed["v"])

    def nddStartGoTo(local_goal, ids_goal, navigating):
        ids_goal.value = dict(local_goal)
        navigating.value = True
        return "plan"
"""
from __future__ import annotations

from typing import Any


class Ref:
    """A holder for an ``out`` or ``inout`` argument: read and assign ``.value``.

    It starts with the variable's current value (a copy), so a codel may also
    change a struct in place (``speed.value["v"] = 0``); whatever ``.value``
    holds when the codel returns is written back.
    """

    __slots__ = ("value",)

    def __init__(self, value: Any = None) -> None:
        self.value = value

    def __repr__(self) -> str:
        return f"Ref({self.value!r})"


class Throw(Exception):
    """Raise it to throw a GenoM exception: ``raise Throw("e_blocked", where={"x": 1.0})``.

    The name may be short (``e_blocked``) or qualified (``NDD::e_blocked``);
    keyword arguments (or a ``detail`` dict) are the exception's members.
    A subclass named after the exception needs no name:
    ``class e_no_goal(Throw): pass`` then ``raise e_no_goal()``.
    """

    def __init__(self, name: str | None = None, detail: dict[str, Any] | None = None, **members: Any) -> None:
        self.name = name or type(self).__name__
        self.detail = {**(detail or {}), **members}
        super().__init__(self.name, self.detail)

    def __str__(self) -> str:
        return f"{self.name} {self.detail}" if self.detail else self.name
