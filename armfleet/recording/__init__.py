"""Recording a world's topics to MCAP, and what to do with a recording: info, plots, replay.

>>> recorder = armfleet.record(world, "run.mcap")      # doctest: +SKIP
>>> world.run(2.0); recorder.stop()                    # doctest: +SKIP
>>> run = armfleet.open_recording("run.mcap")          # doctest: +SKIP
>>> armfleet.plot_recording(run)                       # doctest: +SKIP

Rule: a front end; imports :mod:`armfleet.viewer` (replay) and the world and the
core below; nothing but Foxglove (its encoders), the CLI and the public API import it.
"""

from typing import TYPE_CHECKING

# Eager: the name is also its module's, which a lazy name would leave in its place.
from armfleet.recording.recover import Recovery, recover
from armfleet.runtime.lazy_exports import lazy_exports

if TYPE_CHECKING:  # the names below, for type checkers; loaded on first use
    from armfleet.recording.arm_record import ArmRecord
    from armfleet.recording.errors import (
        DamagedRecording,
        NotARecording,
        RecordingError,
        RecordingNotFound,
        UnknownRecordedArm,
    )
    from armfleet.recording.plot import plot_recording
    from armfleet.recording.reader import RecordedMessage, Recording, TopicInfo, open_recording
    from armfleet.recording.recorder import Recorder, record
    from armfleet.recording.replay import ReplayPlayer, export_html
    from armfleet.recording.replay_stream import replay_events

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "ArmRecord": "armfleet.recording.arm_record",
        "DamagedRecording": "armfleet.recording.errors",
        "NotARecording": "armfleet.recording.errors",
        "RecordingError": "armfleet.recording.errors",
        "RecordingNotFound": "armfleet.recording.errors",
        "UnknownRecordedArm": "armfleet.recording.errors",
        "plot_recording": "armfleet.recording.plot",
        "RecordedMessage": "armfleet.recording.reader",
        "Recording": "armfleet.recording.reader",
        "TopicInfo": "armfleet.recording.reader",
        "open_recording": "armfleet.recording.reader",
        "Recorder": "armfleet.recording.recorder",
        "record": "armfleet.recording.recorder",
        "ReplayPlayer": "armfleet.recording.replay",
        "export_html": "armfleet.recording.replay",
        "replay_events": "armfleet.recording.replay_stream",
    },
)

__all__ = [
    "ArmRecord",
    "DamagedRecording",
    "NotARecording",
    "RecordedMessage",
    "Recorder",
    "Recording",
    "RecordingError",
    "RecordingNotFound",
    "Recovery",
    "ReplayPlayer",
    "TopicInfo",
    "UnknownRecordedArm",
    "export_html",
    "open_recording",
    "plot_recording",
    "record",
    "recover",
    "replay_events",
]
