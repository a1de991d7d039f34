"""The OpenAPI 3.1 description of a controller's services interface, made from its interface data.

Each service gets its own path with the JSON schema of its inputs, so a
generic OpenAPI client can send well-formed requests without reading the
GenoM description.
"""
from __future__ import annotations

import re
from typing import Any

from runtime.controller import REPORT_STATUSES, REQUEST_STATUSES


def _name(type_name: str) -> str:
    """OpenAPI component names allow ``[A-Za-z0-9._-]``: ``dala::pose`` → ``dala.pose``."""
    return re.sub(r"[^A-Za-z0-9._-]", ".", type_name.replace("::", "."))


def _refs(schema: Any) -> Any:
    """Interface ``{"$ref": "dala::pose"}`` → ``{"$ref": "#/components/schemas/dala.pose"}``."""
    if isinstance(schema, dict):
        return {k: (f"#/components/schemas/{_name(v)}" if k == "$ref" else _refs(v)) for k, v in schema.items()}
    if isinstance(schema, list):
        return [_refs(v) for v in schema]
    return schema


def _json(schema: dict[str, Any] | str) -> dict[str, Any]:
    if isinstance(schema, str):
        schema = {"$ref": f"#/components/schemas/{schema}"}
    return {"application/json": {"schema": schema}}


def _error(description: str) -> dict[str, Any]:
    return {"description": description, "content": _json("Error")}


_GENERIC_SCHEMAS: dict[str, Any] = {
    "Error": {"type": "object", "required": ["error", "status"],
              "properties": {"error": {"type": "string", "description": "what is wrong, naming it"},
                             "status": {"type": "integer"}}},
    "Report": {"type": "object", "required": ["request", "component", "service", "status", "final"],
               "properties": {
                   "request": {"type": "integer"}, "component": {"type": "string"}, "service": {"type": "string"},
                   "status": {"enum": list(REPORT_STATUSES)},
                   "final": {"type": "boolean"}, "step": {"type": "integer"}, "time": {"type": "number"},
                   "message": {"type": "string"}, "outputs": {"type": "object"},
                   "reason": {"enum": ["rule", "validate"]}, "rule": {"type": "string"},
                   "rules": {"type": "array", "items": {"type": "string"}},
                   "status_of": {"type": "object"}, "exception": {"type": "string"}, "detail": {"type": "object"},
                   "codel": {"type": "string"}, "error": {"type": "string"},
                   "by": {"type": ["string", "null"]}, "by_request": {"type": ["integer", "null"]}}},
    "Request": {"type": "object", "required": ["id", "component", "service", "status", "reports"],
                "properties": {"id": {"type": "integer"}, "component": {"type": "string"},
                               "service": {"type": "string"}, "inputs": {"type": "object"},
                               "status": {"enum": list(REQUEST_STATUSES)},
                               "final": {"anyOf": [{"$ref": "#/components/schemas/Report"}, {"type": "null"}]},
                               "reports": {"type": "array", "items": {"$ref": "#/components/schemas/Report"}}}},
    "Accepted": {"type": "object", "properties": {"id": {"type": "integer"}, "status": {"const": "queued"},
                                                  "url": {"type": "string"}}},
    "Poster": {"type": "object", "properties": {"component": {"type": "string"}, "port": {"type": "string"},
                                                "value": {}, "seq": {"type": "integer"},
                                                "written": {"type": "boolean"}}},
}


def openapi(interface: dict[str, Any]) -> dict[str, Any]:
    """The OpenAPI document: generic routes, then one path per service with its inputs' schema."""
    schemas = dict(_GENERIC_SCHEMAS)
    for name, schema in interface.get("types", {}).items():
        schemas[_name(name)] = _refs(schema)
    wait = {"name": "wait", "in": "query", "required": False, "schema": {"type": "number", "maximum": 60},
            "description": "wait up to this many seconds for the final report"}
    paths: dict[str, Any] = {
        "/": {"get": {"summary": "the controller: status, steps, requests, codels",
                      "responses": {"200": {"description": "summary"}}}},
        "/components": {"get": {"summary": "components, their services and posters",
                                "responses": {"200": {"description": "list"}}}},
        "/components/{component}": {"get": {
            "summary": "one component: services with parameter schemas, ports, tasks",
            "parameters": [{"name": "component", "in": "path", "required": True, "schema": {"type": "string"}}],
            "responses": {"200": {"description": "component"}, "404": _error("no such component")}}},
        "/requests": {"get": {"summary": "recent requests", "parameters": [
            {"name": "status", "in": "query", "schema": {"enum": list(REQUEST_STATUSES)}},
            {"name": "limit", "in": "query", "schema": {"type": "integer", "minimum": 1}}],
            "responses": {"200": {"description": "list"},
                          "400": _error("a status no request has, a limit that is not a number from 1")}}},
        "/requests/{id}": {"get": {
            "summary": "a request and its reports", "parameters": [
                {"name": "id", "in": "path", "required": True, "schema": {"type": "integer"}}, wait],
            "responses": {"200": {"description": "request", "content": _json("Request")},
                          "400": _error("not a request id"), "404": _error("no such request")}}},
        "/events": {"get": {
            "summary": "server-sent events: report, service, poster, overrun, codel_error, codel_overrun, observer, "
                       "controller",
            "parameters": [{"name": "types", "in": "query", "schema": {"type": "string"},
                            "description": "comma-separated event types (default: all)"}],
            "responses": {"200": {"description": "an event stream", "content": {"text/event-stream": {}}},
                          "400": _error("an unknown event type")}}},
        "/tasks": {"get": {"summary": "periods, lateness and overruns of every task",
                           "responses": {"200": {"description": "list"}}}},
        "/live/": {"get": {"summary": "the live page (HTML; its files need no token, its data does)",
                           "responses": {"200": {"description": "the page", "content": {"text/html": {}}}}}},
        "/pictures/level.svg": {"get": {
            "summary": "the functional level as `genom2bip graph` draws it, for the live page",
            "responses": {"200": {"description": "SVG", "content": {"image/svg+xml": {}}},
                          "503": _error("no Graphviz layout engine")}}},
        "/pictures/modules/{module}.svg": {"get": {
            "summary": "one module as a compound (Fig. 7), for the live page",
            "parameters": [{"name": "module", "in": "path", "required": True, "schema": {"type": "string"}}],
            "responses": {"200": {"description": "SVG", "content": {"image/svg+xml": {}}},
                          "404": _error("no such module"), "503": _error("no Graphviz layout engine")}}},
        "/scene": {"get": {"summary": "the world of a mission run with --view, for the live page",
                           "responses": {"200": {"description": "bounds, obstacles, goals"},
                                         "404": _error("no mission")}}},
    }
    for cname, comp in interface["components"].items():
        for pname, port in comp["ports"].items():
            if port["direction"] == "out":
                paths[f"/components/{cname}/ports/{pname}"] = {"get": {
                    "summary": f"poster {cname}.{pname}", "tags": [cname],
                    "responses": {"200": {"description": "the last written value", "content": _json("Poster")},
                                  "404": _error("no such poster")}}}
        for sname, svc in comp["services"].items():
            inputs = [p for p in svc["parameters"] if p["direction"] in ("in", "inout")]
            body = {"type": "object", "additionalProperties": False,
                    "properties": {p["name"]: _refs(p["schema"]) | ({"default": p["default"]} if "default" in p else {})
                                   | ({"description": p["doc"]} if p.get("doc") else {}) for p in inputs},
                    "required": [p["name"] for p in inputs if "default" not in p]}
            paths[f"/components/{cname}/services/{sname}"] = {
                "get": {"summary": f"{cname}.{sname}: its parameters", "tags": [cname],
                        "responses": {"200": {"description": "service"}}},
                "post": {
                    "summary": f"send a request to {svc['kind']} {cname}.{sname}", "tags": [cname],
                    "description": svc.get("doc") or "", "parameters": [wait],
                    "requestBody": {"required": True, "content": _json(body),
                                    "description": "the inputs; {} for the defaults (a POST without "
                                                   "application/json is refused: a cross-site form could send it)"},
                    "responses": {
                        "202": {"description": "queued", "content": _json("Accepted")},
                        "200": {"description": "with wait: the request and its reports", "content": _json("Request")},
                        "400": _error("malformed JSON"),
                        "409": _error("an activity already handling a request"),
                        "422": _error("unknown, missing or ill-typed parameters"),
                        "413": _error("a body longer than 1 MiB"),
                        "415": _error("a body not sent as application/json"),
                        "429": _error("too many requests waiting to be taken"),
                        "503": _error("the controller has stopped")}}}
    return {
        "openapi": "3.1.0",
        "info": {"title": f"{interface.get('system', 'BIP')} controller: services interface", "version": "1",
                 "description": "GenoM-style services of a BIP controller generated by genom2bip (docs/runtime.md)."},
        "servers": [{"url": "/"}],
        "paths": paths,
        "components": {"schemas": schemas},
    }
