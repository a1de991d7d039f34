"""What the services interface shows of components and services: the interface data, shaped for clients."""
from __future__ import annotations

from typing import Any


def _param(p: dict[str, Any]) -> dict[str, Any]:
    out = {"name": p["name"], "schema": p["schema"]}
    for key in ("default", "doc"):
        if key in p:
            out[key] = p[key]
    out["required"] = "default" not in p and p["direction"] in ("in", "inout")
    return out


def service_view(interface: dict[str, Any], component: str, service: str) -> dict[str, Any]:
    """A service as a client needs it: kind, inputs and outputs with their schemas, exceptions, constraints."""
    s = interface["components"][component]["services"][service]
    params = s["parameters"]
    return {
        "component": component, "name": service, "kind": s["kind"], "doc": s.get("doc"), "task": s.get("task"),
        "reentrant": s["kind"] != "activity",
        "inputs": [_param(p) for p in params if p["direction"] in ("in", "inout")],
        "outputs": [_param(p) | {"required": False} for p in params if p["direction"] in ("out", "inout")],
        "throws": s["throws"], "interrupts": s["interrupts"], "after": s["after"], "before": s["before"],
        "url": f"/components/{component}/services/{service}",
    }


def component_view(interface: dict[str, Any], component: str) -> dict[str, Any]:
    c = interface["components"][component]
    return {
        "name": component, "doc": c.get("doc"),
        "services": [service_view(interface, component, s) for s in c["services"]],
        "ports": [{"name": p, "direction": x["direction"], "schema": x["schema"]}
                  | ({"url": f"/components/{component}/ports/{p}"} if x["direction"] == "out" else {})
                  for p, x in c["ports"].items()],
        "tasks": [{"name": t, "period_ms": x["period_us"] / 1e3 if x["period_us"] else None}
                  for t, x in c["tasks"].items()],
        "exceptions": c.get("exceptions", {}),
        "types": interface.get("types", {}),
    }


def components_view(interface: dict[str, Any]) -> list[dict[str, Any]]:
    return [{"name": name, "doc": c.get("doc"), "services": list(c["services"]),
             "posters": [p for p, x in c["ports"].items() if x["direction"] == "out"], "url": f"/components/{name}"}
            for name, c in interface["components"].items()]
