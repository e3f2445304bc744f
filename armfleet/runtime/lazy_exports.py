"""Names a package re-exports, loaded on first use (PEP 562).

A room's ``__init__`` lists its public names and the modules that define them; a name's
module is imported only when the name is first read. So importing one light module of a
room (``armfleet.planning.failure``, say) does not load the whole room (OMPL, coal), and a
command-line call that only talks to a running world starts without the simulator.
Type checkers and import-linter read the same names from the ``TYPE_CHECKING`` block
beside the table.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Mapping
from typing import Any


def lazy_exports(
    package: str, exports: Mapping[str, str]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``(__getattr__, __dir__)`` for ``package``: each name of ``exports`` (name -> module
    defining it) is imported from its module when first read, then kept in the package."""

    def get_attribute(name: str) -> Any:
        module = exports.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module), name)
        setattr(sys.modules[package], name, value)
        return value

    def names() -> list[str]:
        return sorted({*vars(sys.modules[package]), *exports})

    return get_attribute, names
