"""``genom2bip call URL Module.Service key=value ... [--wait]``: one request to a running controller.

Values are JSON when they parse as JSON (``v=0.2``, ``goal='{"x": 1, "y": 0, "theta": 0}'``),
strings otherwise (``device=/dev/ttyS0``); a dotted key sets a member
(``goal.x=1 goal.y=2``; members left out keep their default).  Without a
service, lists the components and services with their inputs.
"""
from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from genom2bip.cli.verbs import EXIT_ERRORS, EXIT_INCONCLUSIVE, EXIT_OK, EXIT_USAGE, EXIT_VIOLATED, error, verb

#: A final report's status -> the exit status (runtime/exits.py): refused is the request not taken (its inputs, a
#: rule), as an input is refused; failed and interrupted are what the run found.
CALL_EXITS = {"ok": EXIT_OK, "rejected": EXIT_ERRORS, "failed": EXIT_VIOLATED, "interrupted": EXIT_VIOLATED}


#: Seconds --timeout may wait at most: a week (no --timeout waits as long as needed).
MAX_TIMEOUT = 7 * 86400.0


def parse_assignments(items: list[str]) -> dict[str, Any]:
    """``["goal.x=1", "name=foo"]`` → ``{"goal": {"x": 1}, "name": "foo"}``."""
    out: dict[str, Any] = {}
    for item in items:
        key, eq, text = item.partition("=")
        if not eq or not key:
            raise ValueError(f"{item!r}: key=value expected")
        try:
            value = json.loads(text)
        except json.JSONDecodeError:
            value = text
        target = out
        parts = key.split(".")
        for i, part in enumerate(parts[:-1]):
            node = target.setdefault(part, {})
            if not isinstance(node, dict):
                raise ValueError(f"{item!r}: {'.'.join(parts[:i + 1])} is already set to {node!r}")
            target = node
        if isinstance(target.get(parts[-1]), dict) and isinstance(value, dict):
            target[parts[-1]].update(value)
        else:
            target[parts[-1]] = value
    return out


def _arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("url", metavar="URL", help="the services interface, e.g. http://127.0.0.1:8080")
    parser.add_argument("target", metavar="Module.Service", nargs="?", help="the service (none: list them)")
    parser.add_argument("params", metavar="key=value", nargs="*", help="input parameters")
    parser.add_argument("--json", metavar="OBJECT", help="all inputs as one JSON object (key=value adds to it)")
    parser.add_argument("--wait", action="store_true", help="wait for the final report and print it")
    parser.add_argument("--timeout", type=float, metavar="SECONDS", help="with --wait: give up after this long")


def shown(text: object) -> str:
    """``text`` safe for a terminal: control characters (escape sequences, a carriage return) written as escapes."""
    return "".join(ch if ch.isprintable() else ch.encode("unicode_escape").decode("ascii") for ch in str(text))


def _listing(client) -> str:
    """The components and their services; a reply of another shape is a BadReply, its text made safe to print."""
    from runtime.services.client import BadReply

    lines = []
    try:
        for comp in client.components():
            lines.append(f"{shown(comp['name'])}: {shown(comp.get('doc') or '')}".rstrip(": "))
            for svc in client.component(comp["name"])["services"]:
                inputs = " ".join(shown(p["name"]) + ("" if p["required"] else f"={json.dumps(p.get('default'))}")
                                  for p in svc["inputs"])
                lines.append(f"  {shown(comp['name'])}.{shown(svc['name'])} ({shown(svc['kind'])}) {inputs}".rstrip())
    except (KeyError, TypeError, AttributeError):
        raise BadReply("the components listed are not of the interface's shape") from None
    return "\n".join(lines)


@verb("call", help="send a request to a running controller's services interface (and wait for its report)",
      arguments=_arguments)
def verb_call(args: argparse.Namespace) -> int:
    """Send one request; with --wait print its final report; exit 0 when it ended ok, 1 rejected, 4 failed or
    interrupted, 5 no final report within --timeout."""
    from runtime.services.client import BadReply, Client, ServiceError, parse_target

    if args.timeout is not None and not 0 <= args.timeout <= MAX_TIMEOUT:  # also refuses nan and inf
        error(f"--timeout: a number of seconds from 0 to {MAX_TIMEOUT:g} (a week) expected, got {args.timeout:g}")
        return EXIT_USAGE
    try:
        client = Client(args.url)
        if args.target is None:
            print(_listing(client))
            return EXIT_OK
        component, service = parse_target(args.target)
        inputs = json.loads(args.json) if args.json else {}
        if not isinstance(inputs, dict):
            raise ValueError("--json: a JSON object expected")
        inputs.update(parse_assignments(args.params))
    except (ValueError, json.JSONDecodeError) as exc:
        error(str(exc))
        return EXIT_USAGE
    except ServiceError as exc:
        error(f"{args.url}: {shown(exc.message)}")
        return EXIT_ERRORS
    except BadReply as exc:
        error(f"{args.url}: not a services interface: {exc}")
        return EXIT_ERRORS
    except OSError as exc:
        error(f"cannot reach {args.url}: {exc.strerror or exc}")
        return EXIT_ERRORS
    try:
        rid = client.send(component, service, inputs)
        if not args.wait:
            print(json.dumps({"id": rid, "status": "queued", "url": f"{client.url}/requests/{rid}"}))
            return EXIT_OK
        report = client.wait(rid, args.timeout)
    except ServiceError as exc:
        error(f"{args.target}: {shown(exc.message)}")
        return EXIT_ERRORS
    except BadReply as exc:
        error(f"{args.url}: not a services interface: {exc}")
        return EXIT_ERRORS
    except TimeoutError as exc:  # no answer yet: the request goes on in the controller
        error(shown(exc))
        return EXIT_INCONCLUSIVE
    except OSError as exc:
        error(f"cannot reach {args.url}: {exc.strerror or exc}")
        return EXIT_ERRORS
    json.dump(report, sys.stdout, indent=2)  # ASCII: a control character in it is written as an escape
    sys.stdout.write("\n")
    return CALL_EXITS.get(report.get("status"), EXIT_VIOLATED)
