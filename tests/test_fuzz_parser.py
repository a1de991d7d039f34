"""Property: whatever is done to a valid description, reading it raises DiagnosticError or nothing.

Valid GenoM2 and GenoM3 files are mutated (tokens or characters deleted,
inserted, duplicated, swapped); parsing, checking, summarising and dumping as
JSON must then either succeed or raise a DiagnosticError whose every
diagnostic names a file, a line and a column -- never another exception.
"""
import re
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from genom2bip.checks import check_description
from genom2bip.ir import to_json
from genom2bip.parser import parse_text
from genom2bip.summary import description_summary
from runtime.diagnostics import DiagnosticError, Reporter

ROOT = Path(__file__).resolve().parents[1]
GENOM2 = ROOT / "tests" / "fixtures" / "genom2" / "rflex.gen"
GENOM3 = ROOT / "descriptions" / "dala" / "NDD.gen"
SEEDS = [(GENOM2, GENOM2.read_text()), (GENOM3, GENOM3.read_text())]

TOKEN = re.compile(r'"(?:\\.|[^"\\\n])*"|[A-Za-z_]\w*|\d+(?:\.\d*)?|::|/\*|\*/|\s+|.', re.S)
INSERTS = [
    "{", "}", ";", ":", "::", ",", "(", ")", "<", ">", "[", "]", "=", "*", "-", "\"", "'", "/*", "*/", "//",
    "\n#include \"rflexStruct.h\"\n", "\n#define X 3\n", "\n#if 0\n", "\n#endif\n", "\n#pragma requires x\n",
    "request", "exec_task", "poster", "module", "component", "activity", "function", "attribute", "task",
    "codel", "yield", "pause::", "ether", "start", "stop", "period", "type", "struct", "typedef", "enum",
    "exec", "control", "init", "all", "wcet", "ms", "0", "-1", "1e400", "0x", "99999999999999999999",
    "@", "$", "\\", "\x00", "\t", "é", "interrupts", "after", "throw", "ids", "port", "out", "in",
]


def tokens(text: str) -> list[str]:
    return TOKEN.findall(text)


@st.composite
def mutated(draw):
    path, text = draw(st.sampled_from(SEEDS))
    by_char = draw(st.booleans())
    parts = list(text) if by_char else tokens(text)
    for _ in range(draw(st.integers(1, 4))):
        if not parts:
            break
        op = draw(st.sampled_from(["delete", "insert", "duplicate", "swap"]))
        i = draw(st.integers(0, len(parts) - 1))
        if op == "delete":
            del parts[i:i + draw(st.integers(1, 3))]
        elif op == "insert":
            parts.insert(i, draw(st.sampled_from(INSERTS)))
        elif op == "duplicate":
            parts.insert(i, parts[i])
        else:
            j = draw(st.integers(0, len(parts) - 1))
            parts[i], parts[j] = parts[j], parts[i]
    return path, "".join(parts)


def read_everything(path: Path, text: str) -> None:
    """What `genom2bip check` does with a file; DiagnosticError is the only way to fail."""
    description = parse_text(text, str(path))
    reporter = Reporter()
    check_description(description, reporter)
    description_summary(description)
    to_json(description)
    reporter.raise_if_errors()


@settings(max_examples=400, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(mutated())
def test_mutated_descriptions_only_raise_diagnostics(case):
    path, text = case
    try:
        read_everything(path, text)
    except DiagnosticError as err:
        assert err.diagnostics, "a DiagnosticError must carry diagnostics"
        n_lines = text.count("\n") + 1
        for diag in err.diagnostics:
            span = diag.span
            assert isinstance(span.file, str) and span.file, diag
            assert span.line >= 1 and span.column >= 1, diag
            if span.file == str(path):
                assert span.line <= n_lines + 1, diag
            diag.render(err.sources)  # rendering never fails either


def test_the_seeds_are_valid():
    for path, text in SEEDS:
        read_everything(path, text)
