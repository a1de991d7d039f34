"""Remote services: a codel calls a service of another component through the controller and waits for its report.

A component that ``uses`` an interface may call the interface's services from its codels (a ``remote``
argument, GenoM3's remote objects).  The call is synchronous, as in GenoM3: it becomes a request to the
component that provides the interface, the calling codel waits for its final report, then gets the
service's outputs (or its exception, with the detail).  While it waits, the engine goes on without it (the
codel is detached, runtime.controller.takeover), so the other component's service can run at all.

Which component serves a remote: by default the only other component of the level that provides the
remote's interface and has the service; :meth:`Remotes.connect` names one (GenoM3's ``connect_service``).
A remote no component serves answers ``genom::no_such_remote``; a request the server does not accept, or
that does not end ``ok`` without an exception of its own, answers ``genom::remote_io``; both with a
``what`` saying why.
"""
from __future__ import annotations

from typing import Any, Callable

from runtime.genom import Throw

NO_SUCH_REMOTE = "genom::no_such_remote"
REMOTE_IO = "genom::remote_io"


class Remote:
    """The handle a codel gets for one remote: ``Add(a=1.0, b=2.0)`` returns the outputs, or raises :class:`Throw`.

    ``parameters`` are the remote service's, as the interface gives them (name, direction, schema).
    """

    def __init__(self, component: str, name: str, parameters: list[dict[str, Any]],
                 call: Callable[[str, str, dict[str, Any]], dict[str, Any]]) -> None:
        self.component, self.name, self.parameters = component, name, parameters
        self._call = call

    def __call__(self, **inputs: Any) -> dict[str, Any]:
        return self._call(self.component, self.name, inputs)

    def __repr__(self) -> str:
        return f"Remote({self.component}.{self.name})"


class Remotes:
    """Every component's remotes, the service each reaches, and the handles codels get (made once each)."""

    def __init__(self, interface: dict[str, Any], call: Callable[[str, str, dict[str, Any]], dict[str, Any]]) -> None:
        comps = interface["components"]
        self.specs: dict[tuple[str, str], dict[str, Any]] = {
            (c, r): spec for c, comp in comps.items() for r, spec in comp.get("remotes", {}).items()}
        self.targets: dict[tuple[str, str], tuple[str, str] | None] = {}
        self.services = {(c, s) for c, comp in comps.items() for s in comp["services"]}
        for (c, r), spec in self.specs.items():
            servers = [o for o, comp in comps.items() if o != c and spec["interface"] in comp.get("provides", ())
                       and r in comp["services"]]
            self.targets[(c, r)] = (servers[0], r) if len(servers) == 1 else None
        self._call = call
        self._handles: dict[tuple[str, str], Remote] = {}

    def connect(self, component: str, remote: str, target: str) -> None:
        """Make ``component``'s remote ``remote`` call the service ``target`` (``"server.Add"``)."""
        if (component, remote) not in self.specs:
            known = ", ".join(r for c, r in self.specs if c == component) or "none"
            raise KeyError(f"{component} has no remote named {remote!r} (remotes: {known})")
        tc, _, ts = target.partition(".")
        if (tc, ts) not in self.services:
            raise KeyError(f"no service {target!r} to connect {component}.{remote} to")
        self.targets[(component, remote)] = (tc, ts)

    def target(self, component: str, remote: str) -> tuple[str, str] | None:
        return self.targets.get((component, remote))

    def why_unconnected(self, component: str, remote: str) -> str:
        spec = self.specs.get((component, remote))
        if spec is None:
            return f"{component} has no remote {remote}"
        return (f"remote {remote} of {component} is connected to no service: no single other component provides "
                f"{spec['interface']} with a service {remote}")

    def handle(self, component: str, remote: str) -> Remote | None:
        """What a codel's ``remote`` argument gets (None for a name the component has no remote of)."""
        key = (component, remote)
        if key not in self.specs:
            return None
        if key not in self._handles:
            self._handles[key] = Remote(component, remote, self.specs[key]["parameters"], self._call)
        return self._handles[key]


def remote_outcome(final: dict[str, Any] | None, target: str) -> dict[str, Any]:
    """The outputs of a remote call's final report; :class:`Throw` for its exception or its failure."""
    if final is None:
        raise Throw(REMOTE_IO, what=f"{target}: the controller stopped before the request ended")
    if final.get("status") == "ok" and not final.get("exception"):
        return dict(final.get("outputs") or {})
    if final.get("exception"):
        raise Throw(final["exception"], detail=dict(final.get("detail") or {}))
    said = final.get("message") or final.get("error") or final.get("status")
    raise Throw(REMOTE_IO, what=f"{target} ended {final.get('status')}: {said}")
