"""Our ``<comp>_c_types.h`` against genom3's, on every component of a corpus (a script, not a test).

    PYTHONPATH=. python bench/genom3_headers.py GENOM3_BUILD_DIR CORPUS_DIR [--show N]

GENOM3_BUILD_DIR is where genom3 was installed (``bin/genom3`` in it; docs/codels.md says how to build it
outside the repository); CORPUS_DIR holds GenoM3 components (any depth; every ``.gen`` that declares a
component).  For each ``.gen`` the script runs ``genom3 mappings --signature -l c`` (what genom3's skeleton
compiles codels against; the packages a component requires are found by pkg-config, so PKG_CONFIG_PATH
may point at stub ``.pc`` files whose Cflags give the include folders) and our generator (``-I DIR``), splits
both headers into declarations keyed by the name they declare, and prints what only genom3 declares, what
only we declare, and the declarations that differ (whitespace, comments and ``#line`` aside).
Nothing is built or written.
"""
from __future__ import annotations

import argparse
import re
import subprocess
import sys
from collections import Counter
from pathlib import Path

from genom2bip.back.c_types import CMappingError, c_types_header
from genom2bip.parser import parse_paths
from runtime.diagnostics import DiagnosticError

GUARD = re.compile(r"#ifndef _(\w+)_c_type\s*\n# ?define _\1_c_type\n(.*?)\n#endif /\* _\1_c_type \*/", re.S)
SIGNATURE = re.compile(r"extern \"C\" \{\s*#endif\s*(.*?);\s*#ifdef __cplusplus", re.S)


def normal(text: str) -> str:
    """A declaration without comments, ``#line`` directives and spacing differences."""
    text = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)
    text = re.sub(r"^#line .*$", " ", text, flags=re.M)
    text = re.sub(r"\s+", " ", text).strip()
    return re.sub(r"\s*([(){}\[\];,*=])\s*", r"\1", text)


def declarations(header: str) -> dict[str, str]:
    """Guard name (or ``codel:NAME``) → the normalised declaration."""
    out = {name: normal(body) for name, body in GUARD.findall(header)}
    for sig in SIGNATURE.findall(header):
        name = re.search(r"(\w+)\s*\(", sig)
        if name:
            out[f"codel:{name.group(1)}"] = normal(sig)
    return out


def genom3_header(genom3: Path, gen: Path) -> tuple[str | None, str]:
    """genom3's mapping of ``gen`` (None and its message when genom3 refuses the file)."""
    cmd = [str(genom3 / "bin" / "genom3"), "mappings", "--signature", "-l", "c", str(gen.resolve())]
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=300, cwd=gen.parent,
                              stdin=subprocess.DEVNULL)  # genom3 reads its standard input for a file it cannot find
    except (OSError, subprocess.TimeoutExpired) as err:
        return None, str(err)
    if done.returncode != 0:
        return None, (done.stderr.strip().splitlines() or ["exit status " + str(done.returncode)])[-1]
    return done.stdout, ""


def ours(gen: Path, include: list[str]) -> dict[str, str] | str:
    """Our header per component of ``gen`` (component → text), or why we refuse it."""
    try:
        description = parse_paths([str(gen)], include_dirs=include)
    except DiagnosticError as err:
        return str(err).splitlines()[0]
    out = {}
    for c in description.components:
        try:
            out[c.name] = c_types_header(description, c, str(gen))
        except CMappingError as err:
            return str(err)
    return out


def compare(theirs: str, mine: str, show: int) -> tuple[list[str], Counter]:
    t, m = declarations(theirs), declarations(mine)
    lines, kinds = [], Counter()
    only_t = [k for k in t if k not in m]
    only_m = [k for k in m if k not in t]
    differ = [k for k in t if k in m and t[k] != m[k]]
    same = sum(1 for k in t if k in m and t[k] == m[k])
    kinds.update({"same": same, "only genom3": len(only_t), "only ours": len(only_m), "differ": len(differ)})
    for label, names in (("only in genom3's", only_t), ("only in ours", only_m)):
        if names:
            more = " ..." if len(names) > show else ""
            lines.append(f"    {label} ({len(names)}): {', '.join(names[:show])}{more}")
    for k in differ[:show]:
        lines.append(f"    {k} differs:\n      genom3: {t[k][:300]}\n      ours:   {m[k][:300]}")
    if len(differ) > show:
        lines.append(f"    ... and {len(differ) - show} more that differ")
    return lines, kinds


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("genom3", type=Path, help="where genom3 is installed (bin/genom3)")
    parser.add_argument("corpus", type=Path, help="a folder of GenoM3 components")
    parser.add_argument("-I", dest="include", action="append", default=[], metavar="DIR",
                        help="an include folder for our parser (genom3 finds its own through pkg-config's "
                             "PKG_CONFIG_PATH, from the components' #pragma require)")
    parser.add_argument("--show", type=int, default=5, help="how many differing declarations to print per component")
    args = parser.parse_args(argv)
    if not (args.genom3 / "bin" / "genom3").is_file():
        print(f"{args.genom3}: no bin/genom3 here (build genom3 first: docs/codels.md)", file=sys.stderr)
        return 2
    gens = sorted(p for p in args.corpus.rglob("*.gen") if re.search(r"^\s*component\s", p.read_text(
        errors="replace"), re.M))
    total: Counter = Counter()
    refused = 0
    for gen in gens:
        rel = gen.relative_to(args.corpus)
        theirs, why = genom3_header(args.genom3, gen)
        if theirs is None:
            print(f"{rel}: genom3 refuses it ({why}): skipped")
            refused += 1
            continue
        mine = ours(gen, args.include)
        if isinstance(mine, str):
            print(f"{rel}: genom3 accepts it, we refuse it: {mine}")
            total["we refuse"] += 1
            continue
        merged = "\n".join(mine.values())
        lines, kinds = compare(theirs, merged, args.show)
        total.update(kinds)
        print(f"{rel}: {', '.join(mine)}: {kinds['same']} declarations alike, {kinds['differ']} differ, "
              f"{kinds['only genom3']} only in genom3's, {kinds['only ours']} only in ours")
        for line in lines:
            print(line)
    print(f"\n{len(gens)} files, {refused} refused by genom3; declarations: " +
          ", ".join(f"{v} {k}" for k, v in sorted(total.items())))
    return 0


if __name__ == "__main__":
    sys.exit(main())
