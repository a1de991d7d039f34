"""The inputs a mission's steps send (``with:``), checked against the services' interface before anything runs.

The controller checks a request's inputs when it arrives (422 naming every
problem, runtime/controller/intake.py); a mission gets the same check, from
the same code, before it starts, and so does ``verify --client`` on the
description's interface: one mission file means one thing to both.
"""
from __future__ import annotations

from typing import Any

from genom2bip.mission.spec import Mission
from runtime.controller.intake import inputs_of
from runtime.diagnostics import Reporter


def check_inputs(mission: Mission, interface: dict[str, Any], reporter: Reporter) -> None:
    """Report, at its ``with:``, every send step whose inputs the controller of ``interface`` would refuse.

    ``interface``: what a generated package holds as ``INTERFACE`` (genom2bip/back/interface.py); a service
    it lacks is left to whoever says so (``verify --client``: "no service"; a mission: the controller's 404).
    """
    types = interface.get("types", {})
    for step in mission.steps:
        if step.kind != "send":
            continue
        component, _, service = step.target.partition(".")
        spec = interface["components"].get(component, {}).get("services", {}).get(service)
        if spec is None:
            continue
        ids = {name: member["initial"] for name, member in interface["components"][component]["ids"].items()}
        _, problems = inputs_of(step.target, spec, step.inputs, types, ids)
        if problems:
            reporter.error(step.inputs_span or step.span, f"with: the controller would refuse this request to "
                                                          f"{step.target}: " + "; ".join(problems))
