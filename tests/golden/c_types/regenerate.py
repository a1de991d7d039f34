"""Rewrite the golden C mapping headers: ``PYTHONPATH=. python tests/golden/c_types/regenerate.py``."""
from pathlib import Path

from genom2bip.back.c_types import c_types_header
from genom2bip.parser import parse_paths

HERE = Path(__file__).parent
FIXTURES = HERE.parents[1] / "fixtures" / "ccodels"

for relative, component in [("mapping/mapping.gen", "mapping"), ("cdemo/cdemo.gen", "cdemo")]:
    description = parse_paths([str(FIXTURES / relative)])
    text = c_types_header(description, description.component(component), f"tests/fixtures/ccodels/{relative}")
    (HERE / f"{component}_c_types.h").write_text(text)
    print(f"wrote {HERE / f'{component}_c_types.h'}")
