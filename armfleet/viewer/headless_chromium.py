"""How to open the viewer in Debian's Chromium without a display (tests, benchmarks).

Software WebGL through SwiftShader; ``--use-gl=swiftshader`` renders an all-white
page there, so it is not among the flags.
"""

from __future__ import annotations

from pathlib import Path

#: Debian's ``chromium`` package (never a browser downloaded by Playwright).
CHROMIUM = Path("/usr/bin/chromium")
#: Flags for a headless run that draws the MeshCat scene and talks to nothing outside.
CHROMIUM_FLAGS = (
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--enable-unsafe-swiftshader",
)
