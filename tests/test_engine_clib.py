"""C's printf, bound by default to models that declare it as an extern function."""
import subprocess
import sys
from pathlib import Path

import pytest

from runtime.engine.clib import c_format

ROOT = Path(__file__).resolve().parents[1]

MODEL = """@cpp(include="stdio.h")
package Printing
  extern function printf(string, int, float)
  port type Port()
  connector type One(Port p)
    define p
  end
  atom type Counter()
    data int n
    export port Port tick()
    place S
    initial to S do { n = 0; }
    on tick from S to S provided (n < 3) do { n = n + 1; printf("n=%d of %5.2f%%\\n", n, 3.0); }
  end
  compound type System()
    component Counter c()
    connector One t(c.tick)
  end
end
"""


@pytest.mark.parametrize("fmt, args, text", [
    ("%d.s1=%d;\n", (1, 5050), "1.s1=5050;\n"),
    ("%ld|%5.1f|%-3s|%x|%u|%c|%%", (7, 2.25, "ab", 255, -1, 65), "7|  2.2|ab |ff|4294967295|A|%"),
    ("%i %d", (3, 2.9), "3 2"),
])
def test_c_conversions(fmt, args, text):
    assert c_format(fmt, args) == text


def test_a_missing_argument_is_named():
    with pytest.raises(ValueError, match="printf: no argument for '%d' in 'a %d'"):
        c_format("a %d", ())


def test_a_model_that_declares_printf_prints_without_bindings(tmp_path):
    (tmp_path / "Printing.bip").write_text(MODEL)
    r = subprocess.run([sys.executable, "-m", "runtime", "run", str(tmp_path / "Printing.bip"), "--quiet"],
                       capture_output=True, text=True, cwd=ROOT, env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"})
    assert r.returncode == 0, r.stderr
    assert r.stdout == "n=1 of  3.00%\nn=2 of  3.00%\nn=3 of  3.00%\n3 steps, deadlock (no enabled interaction)\n"


def test_a_binding_given_by_the_user_wins():
    from runtime.bip2 import parse_text
    from runtime.engine import Engine

    seen = []
    engine = Engine(parse_text(MODEL, "Printing.bip"), "System()", externs={"printf": lambda *a: seen.append(a)})
    state = engine.fire(engine.initial_state(), engine.find(engine.initial_state(), "t"))
    assert seen == [("n=%d of %5.2f%%\n", 1, 3.0)] and engine.describe_state(state)["c"]["data"] == {"n": 1}
