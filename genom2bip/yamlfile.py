"""Reading a YAML input (rules, observers, missions, worlds): its node tree with positions, or located errors.

Every problem is a diagnostic at ``file:line:column``, never an exception
from PyYAML: a file that is not UTF-8 text or not a regular file, one larger
than :data:`MAX_YAML_BYTES`, a control character (a NUL byte), collections
nested deeper than :data:`MAX_NESTING` (composing recurses), anchors and
aliases expanding to more than :data:`MAX_NODES` values, a number that is
not finite (``.nan``, ``.inf``, ``1e400``) or an integer of more than 64 bits,
a key that is a list or a mapping (``? [a]``: no reader could look it up).
:func:`keyed` reports a key given twice, which PyYAML would merge without a word.
"""
from __future__ import annotations

import math
import os
from pathlib import Path

import yaml

from runtime.diagnostics import DiagnosticError, Reporter, Span
from runtime.textfile import read_text

#: Bytes of one YAML input: the largest of ours (a world) is 2 kB.
MAX_YAML_BYTES = 1 << 20
#: A rule file nests three levels (rules, a rule, a list of services), a world five; composing deeper recurses.
MAX_NESTING = 50
#: Values of a file once its aliases are expanded (an alias of an alias of a list doubles at each level).
MAX_NODES = 100_000
#: The widest integers read: 64 bits.
INT_MIN, INT_MAX = -(2 ** 63), 2 ** 64 - 1

_FLOAT, _INT = "tag:yaml.org,2002:float", "tag:yaml.org,2002:int"


def span_of(path: str | Path, node: yaml.Node) -> Span:
    """The span of a node: from its first character to past its last."""
    m, e = node.start_mark, node.end_mark
    return Span(str(path), m.line + 1, m.column + 1, e.line + 1, e.column + 1)


def _too_deep(text: str):
    """The YAML mark where collections nest deeper than MAX_NESTING (read as events, without recursion), or None."""
    depth = 0
    for event in yaml.parse(text):
        if isinstance(event, yaml.CollectionStartEvent):
            depth += 1
            if depth > MAX_NESTING:
                return event.start_mark
        elif isinstance(event, yaml.CollectionEndEvent):
            depth -= 1
    return None


def _position(text: str, index: int) -> tuple[int, int]:
    """1-based line and column of the character at ``index``."""
    line_start = text.rfind("\n", 0, index) + 1
    return text.count("\n", 0, index) + 1, index - line_start + 1


def _compose(path: Path, text: str) -> tuple[yaml.Node | None, tuple[Span, str] | None]:
    """The node tree of ``text``, or where and why it is not YAML that can be composed safely."""
    try:
        deep = _too_deep(text)
        if deep is not None:
            where = Span(str(path), deep.line + 1, deep.column + 1)
            return None, (where, f"nested more than {MAX_NESTING} levels deep")
        return yaml.compose(text), None
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line, col = (mark.line + 1, mark.column + 1) if mark else (1, 1)
        return None, (Span(str(path), line, col), f"not valid YAML: {exc.problem or exc.context}")
    except yaml.reader.ReaderError as exc:  # a character YAML does not allow: a NUL byte, a control character
        line, col = _position(text, exc.position)
        return None, (Span(str(path), line, col), f"not valid YAML: the character U+{exc.character:04X} is not "
                                                  "allowed")
    except yaml.YAMLError as exc:
        return None, (Span(str(path), 0, 0), f"not valid YAML: {exc}")


def _scalar_problem(node: yaml.ScalarNode) -> str | None:
    """Why a number in the file is not one a reader may take (not finite, wider than 64 bits), or None."""
    if node.tag not in (_FLOAT, _INT):
        return None
    try:
        value = yaml.constructor.SafeConstructor().construct_object(node)
    except ValueError:  # an integer of thousands of digits
        return f"{node.value[:20]}... is out of range: an integer has 64 bits at most"
    if isinstance(value, float) and not math.isfinite(value):
        return f"{node.value} is not a finite number"
    if isinstance(value, int) and not INT_MIN <= value <= INT_MAX:
        return f"{node.value} is out of range: an integer has 64 bits at most"
    return None


def _kind(node: yaml.Node) -> str:
    return "a list" if isinstance(node, yaml.SequenceNode) else "a mapping"


def _keys_problems(path: Path, node: yaml.MappingNode, reporter: Reporter) -> bool:
    """Report the keys of one mapping that are lists or mappings (no reader can look them up); False if any."""
    ok = True
    for key, _ in node.value:
        if not isinstance(key, yaml.ScalarNode):
            reporter.error(span_of(path, key), f"a key is a single value (a name), not {_kind(key)}")
            ok = False
    return ok


def keyed(path: str | Path, node: yaml.MappingNode, reporter: Reporter, what: str) -> dict[str, tuple[yaml.Node,
                                                                                                       yaml.Node]]:
    """The (key, value) nodes of a mapping by key, each key given twice reported at its second place (PyYAML keeps
    the last one without a word); keys are scalars once :func:`compose_file` has read the file."""
    out: dict[str, tuple[yaml.Node, yaml.Node]] = {}
    for key, value in node.value:
        name = str(key.value)
        if name in out:
            reporter.error(span_of(path, key), f"{what}: key {name!r} given twice (first at line "
                                               f"{out[name][0].start_mark.line + 1})")
            continue
        out[name] = (key, value)
    return out


def _values(path: Path, root: yaml.Node | None, reporter: Reporter) -> bool:
    """Check every value of the tree, aliases expanded up to MAX_NODES; False after reporting a problem."""
    stack = [root] if root is not None else []
    seen = 0
    ok = True
    keyed: set[int] = set()  # the mappings whose keys were checked (an alias visits its node again)
    while stack:
        node = stack.pop()
        seen += 1
        if seen > MAX_NODES:
            reporter.error(span_of(path, node), f"more than {MAX_NODES:,} values once anchors and aliases are "
                                                "expanded", "an alias of a list of aliases doubles at each level")
            return False
        if isinstance(node, yaml.MappingNode):
            if id(node) not in keyed:
                keyed.add(id(node))
                ok = _keys_problems(path, node, reporter) and ok
            stack.extend(v for pair in reversed(node.value) for v in reversed(pair))
        elif isinstance(node, yaml.SequenceNode):
            stack.extend(reversed(node.value))
        else:
            problem = _scalar_problem(node)
            if problem:
                reporter.error(span_of(path, node), problem)
                ok = False
    return ok


def compose_file(path: Path, reporter: Reporter, what: str) -> tuple[bool, yaml.Node | None]:
    """A YAML file's node tree (positions kept for messages); (False, None) after reporting a problem."""
    path = Path(path)
    try:
        size = os.stat(path).st_size
    except OSError:
        size = 0  # read_text says why it cannot be read
    if size > MAX_YAML_BYTES:
        reporter.error(Span(str(path), 0, 0), f"not read: {size / 1024 / 1024:.1f} MB is more than the "
                                              f"{MAX_YAML_BYTES // 1024 // 1024} MB a {what} may hold")
        return False, None
    try:
        text = read_text(path, what)
    except DiagnosticError as exc:
        reporter.diagnostics.extend(exc.diagnostics)
        return False, None
    reporter.sources.add(str(path), text)
    root, problem = _compose(path, text)
    if problem is not None:
        span, message = problem
        reporter.error(span, message if not message.startswith("nested") else f"{message}: not a {what}")
        return False, None
    return _values(path, root, reporter), root
