"""docs/foxglove-layout.json at 1400x900: every Service Call button stays on screen (issue
28, item 18: with the old layout, Lichtblick hid both).

No browser here, so the check is a stated model of Lichtblick's Call Service panel
(``panels/CallService/CallService.tsx``): a column of the request and response editors
(side by side in the ``horizontal`` layout, stacked in ``vertical``), each a caption and
a multiline monospace text field growing with its text, then the button row. Each
panel's box comes from the layout's splits in the window left once the app's own bars and
an open sidebar are taken off. The response is the service's real reply, shown as the
panel shows it (``JSON.stringify(response, null, 2)``).
"""

from __future__ import annotations

import json
import math
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

import armfleet
from tests.test_foxglove import FoxgloveClient

LAYOUT = Path(__file__).parents[1] / "docs" / "foxglove-layout.json"

# -- the model [px] -----------------------------------------------------------------------------
WINDOW = (1400, 900)
#: Taken off the window: the app bar and the playback bar (height), an open sidebar (width).
APP_BARS_HEIGHT = 44 + 64
SIDEBAR_WIDTH = 300
PANEL_TOOLBAR = 30
PANEL_PADDING = 12  # theme spacing(1.5), each side
GAP = 8  # spacing(1), between the editors and before the button row
BUTTON_ROW = 37
CAPTION = 20
LINE = 12 * 1.4  # monospace 12 px, line height 1.4
CHAR = 12 * 0.6  # monospace advance
FIELD_PADDING = 8 + 8  # spacing(1) above and below the text, inside the outline


def panel_boxes(node: Any, width: float, height: float) -> dict[str, tuple[float, float]]:
    """Panel id -> (width, height) from the layout's nested splits."""
    if isinstance(node, str):
        return {node: (width, height)}
    share = node.get("splitPercentage", 50) / 100
    if node["direction"] == "row":
        first, second = (share * width, height), ((1 - share) * width, height)
    else:
        first, second = (width, share * height), (width, (1 - share) * height)
    return {**panel_boxes(node["first"], *first), **panel_boxes(node["second"], *second)}


def field_height(text: str, width: float) -> float:
    per_line = max(1, math.floor((width - FIELD_PADDING) / CHAR))
    lines = sum(max(1, math.ceil(len(line) / per_line)) for line in text.split("\n"))
    return lines * LINE + FIELD_PADDING


def height_needed(config: dict[str, Any], response: str, width: float) -> float:
    inner = width - 2 * PANEL_PADDING
    if config.get("layout") == "horizontal":
        column = (inner - GAP) / 2
        editors = CAPTION + max(
            field_height(config["requestPayload"], column), field_height(response, column)
        )
    else:
        editors = (
            2 * CAPTION
            + GAP
            + field_height(config["requestPayload"], inner)
            + field_height(response, inner)
        )
    return PANEL_TOOLBAR + 2 * PANEL_PADDING + editors + GAP + BUTTON_ROW


@pytest.fixture
def client() -> Iterator[FoxgloveClient]:
    """bob and toby served; the world steps in this thread between client reads."""
    world = armfleet.World()
    world.spawn("bob", at=(0, 0))
    world.spawn("toby", at=(1, 0))
    server = world.serve_foxglove(0)
    stop = threading.Event()

    def step() -> None:
        while not stop.is_set() and not world.closed:
            world.run(0.02, realtime=True)

    stepper = threading.Thread(target=step, daemon=True)
    stepper.start()
    try:
        connected = FoxgloveClient.open(server.url)
        yield connected
        connected.close()
    finally:
        stop.set()
        stepper.join(timeout=10)
        world.close()


def test_every_service_call_button_is_on_screen_at_1400x900(client: FoxgloveClient) -> None:
    layout = json.loads(LAYOUT.read_text())
    width, height = WINDOW[0] - SIDEBAR_WIDTH, WINDOW[1] - APP_BARS_HEIGHT
    boxes = panel_boxes(layout["layout"], width, height)
    calls = {name: c for name, c in layout["configById"].items() if name.startswith("CallService!")}
    assert calls and set(calls) <= set(boxes)
    for name, config in calls.items():
        ok, reply = client.call(config["serviceName"], config["requestPayload"].encode())
        assert ok, reply
        shown = json.dumps(json.loads(reply), indent=2)
        box_width, box_height = boxes[name]
        needed = height_needed(config, shown, box_width)
        assert needed <= box_height, f"{name}: needs {needed:.0f} px, has {box_height:.0f}"
