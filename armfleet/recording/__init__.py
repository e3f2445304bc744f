"""Recording a world's topics to MCAP, and what to do with a recording: info, plots, replay.

>>> recorder = armfleet.record(world, "run.mcap")      # doctest: +SKIP
>>> world.run(2.0); recorder.stop()                    # doctest: +SKIP
>>> run = armfleet.open_recording("run.mcap")          # doctest: +SKIP
>>> armfleet.plot_recording(run)                       # doctest: +SKIP

Rule: a front end; imports :mod:`armfleet.viewer` (replay) and the world and the
core below; nothing but Foxglove (its encoders), the CLI and the public API import it.
"""

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
from armfleet.recording.recover import Recovery, recover
from armfleet.recording.replay import ReplayPlayer, export_html
from armfleet.recording.replay_stream import replay_events

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
