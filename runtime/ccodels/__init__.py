"""C and C++ codels under the controller: genom3-compatible headers (include/) and the ctypes binding.

``include/genom3/c/*.h`` are the runtime headers a GenoM3 component's codels include besides its
``<comp>_c_types.h``; :func:`~runtime.ccodels.loading.c_codels` loads each component's codel library and
gives its codels as functions with the same call as Python codels (docs/codels.md).
"""
from pathlib import Path

from runtime.ccodels.loading import c_codels

#: The directory to give the compiler with ``-I`` for ``#include "genom3/c/context.h"``.
INCLUDE = Path(__file__).parent / "include"

__all__ = ["INCLUDE", "c_codels"]
