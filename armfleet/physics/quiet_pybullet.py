"""Import PyBullet without its build-time banner on stderr.

PyBullet's C module prints "pybullet build time: ..." straight to file
descriptor 2 when first imported. armfleet's CLI promises exactly one line on
stderr for a bad invocation, so the first import happens here with fd 2
pointed at /dev/null. Import errors still raise as usual.
"""

from __future__ import annotations

import os
import sys


def import_quietly() -> None:
    """Import :mod:`pybullet` once with the C-level stderr silenced."""
    if "pybullet" in sys.modules:
        return
    sys.stderr.flush()
    saved = os.dup(2)
    try:
        with open(os.devnull, "w") as devnull:
            os.dup2(devnull.fileno(), 2)
            import pybullet  # noqa: F401
    finally:
        os.dup2(saved, 2)
        os.close(saved)
