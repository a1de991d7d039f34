"""Property files (MCL-style, docs/verification/properties.md) read against a model: the checkables the checks take."""
from __future__ import annotations

from pathlib import Path
from typing import Sequence

from genom2bip.loading import Report
from genom2bip.verify.model import Model


def read_properties(model: Model, paths: Sequence[str | Path], report: Report | None = None) -> tuple[list, list]:
    """``(properties, warnings)`` of the files, in order; each file's warnings also go to ``report`` as it is read.

    Raises ``DiagnosticError`` (file:line:column) at the first file with an error.
    """
    from runtime.props import read_property_file

    items, warnings = [], []
    for path in paths:
        props, found = read_property_file(str(path), model.flat)
        if found and report is not None:
            report(found, None)
        warnings.extend(found)
        items.extend(props)
    return items, warnings
