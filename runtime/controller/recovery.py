"""Feedback on a violation: an observer's violation requests a recovery service (paper §VI, error recovery).

``on_violation(controller, ["NDD.motion.overrun=NDD.Stop"])`` makes a
violation of that observer queue a request to ``NDD.Stop``, with its default
parameters; what the request interrupts is the model's business (Stop's
``interrupts``, the rules).  The violation event says which request was sent,
or why none could be.
"""
from __future__ import annotations

from typing import Any

from runtime.controller.requests import RequestError


class RecoveryError(Exception):
    """An --on-violation item that names no observer or no service."""


def on_violation(controller, items: list[str]) -> None:
    """Bind each ``OBSERVER=Component.Service`` item; raises RecoveryError naming what is wrong."""
    if not items:
        return
    monitor = controller.monitor
    names = [w.name for w in monitor.watches] if monitor is not None else []
    for item in items:
        observer, eq, target = item.partition("=")
        component, dot, service = target.partition(".")
        if not eq or not dot:
            raise RecoveryError(f"'{item}' is not OBSERVER=Component.Service")
        if observer not in names:
            raise RecoveryError(f"no observer '{observer}' in the model"
                                + (f" (observers: {', '.join(names)})" if names else
                                   " (generate it with --monitor or --timed)"))
        try:
            controller.service(component, service)
        except RequestError as exc:  # it says which name is unknown
            raise RecoveryError(str(exc)) from None
        monitor.actions[observer] = _requester(controller, component, service)


def _requester(controller, component: str, service: str):
    def request(event: dict[str, Any]) -> dict[str, Any]:
        try:
            req = controller.submit(component, service)
        except RequestError as exc:  # busy, stopping: the event says so, the controller goes on
            return {"service": f"{component}.{service}", "error": str(exc)}
        return {"service": f"{component}.{service}", "request": req.id}
    return request
