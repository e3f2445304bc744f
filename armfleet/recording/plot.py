"""Tracking plots: per joint, the position controller's reference vs the measured position,
and the tracking error, one figure per arm (matplotlib, no display needed).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from armfleet.checks.extras import require_extra
from armfleet.checks.user_paths import given_path
from armfleet.recording.errors import RecordingError
from armfleet.recording.reader import Recording
from armfleet.recording.tracking_data import TrackingData, plottable_arms, tracking_data

#: File types ``plot`` writes.
FORMATS = (".png", ".svg", ".pdf")
WIDTH_IN = 12.0
ROW_IN = 1.6
TITLE_IN = 1.0
DPI = 100
REFERENCE_COLOR = "tab:blue"
MEASURED_COLOR = "tab:orange"
ERROR_COLOR = "tab:red"
COMMAND_COLOR = "tab:gray"


def figure_size_px(joints: int) -> tuple[int, int]:
    """(width, height) in pixels of the figure of an arm with ``joints`` joints."""
    return round(WIDTH_IN * DPI), round((TITLE_IN + ROW_IN * joints) * DPI)


def output_paths(
    recording: Path, arms: Sequence[str], output: str | Path | None
) -> dict[str, Path]:
    """Where each arm's figure goes.

    No ``output``: ``<recording stem>_<arm>.png`` beside the recording. An existing
    directory: the same names in it. A file name: that file for a single arm,
    ``<stem>_<arm><suffix>`` for several.

    Raises:
        RecordingError: a file type matplotlib is not asked to write here.
    """
    if output is None:
        return {arm: recording.with_name(f"{recording.stem}_{arm}.png") for arm in arms}
    target = given_path(output, "output")
    if target.is_dir():
        return {arm: target / f"{recording.stem}_{arm}.png" for arm in arms}
    if target.suffix.lower() not in FORMATS:
        raise RecordingError(
            f"-o {target}: name a {', '.join(FORMATS)} file, or an existing directory"
        )
    if len(arms) == 1:
        return {arms[0]: target}
    return {arm: target.with_name(f"{target.stem}_{arm}{target.suffix}") for arm in arms}


def plot_recording(
    recording: Recording, arms: Sequence[str] | None = None, output: str | Path | None = None
) -> dict[str, Path]:
    """Draw the tracking of ``arms`` (every arm with a recorded controller state by default).

    Returns:
        The figure written for each arm.

    Raises:
        UnknownRecordedArm, RecordingError: an arm that is not there, a recording without
            any controller state, an unwritable output.
    """
    chosen = tuple(arms) if arms else plottable_arms(recording)
    if not chosen:
        raise RecordingError(
            f"{recording.path} has no /<arm>/position_controller/state messages to plot"
        )
    data = [tracking_data(recording, arm) for arm in chosen]  # all errors before any file
    paths = output_paths(recording.path, chosen, output)
    for arm_data in data:
        write_figure(arm_data, paths[arm_data.arm], recording.path.name)
    return paths


def write_figure(data: TrackingData, path: Path, source: str = "") -> None:
    """Write the tracking figure of one arm to ``path``.

    Raises:
        RecordingError: the file cannot be written.
    """
    require_extra("Plotting a recording", "plot", "matplotlib")
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    joints = len(data.joint_names)
    width, height = figure_size_px(joints)
    figure = Figure(figsize=(width / DPI, height / DPI), dpi=DPI)
    FigureCanvasAgg(figure)
    axes = figure.subplots(joints, 2, sharex=True, squeeze=False)
    time = data.time_s
    error = data.error
    for j, name in enumerate(data.joint_names):
        unit, scale, error_unit = ("m", 1e3, "mm") if data.prismatic[j] else ("rad", 1e3, "mrad")
        left, right = axes[j]
        # Measured first, the dashed reference over it: both show where they agree.
        left.plot(time, data.position[:, j], color=MEASURED_COLOR, lw=2.2, label="measured")
        left.plot(
            time, data.reference[:, j], color=REFERENCE_COLOR, lw=1.2, ls="--", label="reference"
        )
        left.set_ylabel(f"{_short(name, data.arm)}\n[{unit}]", fontsize=8)
        right.plot(time, error[:, j] * scale, color=ERROR_COLOR, lw=0.9)
        right.axhline(0.0, color="black", lw=0.5)
        right.set_ylabel(f"error [{error_unit}]", fontsize=8)
        for ax in (left, right):
            for t in data.command_times_s:
                ax.axvline(t, color=COMMAND_COLOR, lw=0.8, ls=":")
            ax.tick_params(labelsize=7)
            ax.grid(True, lw=0.3, alpha=0.6)
    axes[0][0].set_title("reference vs measured position", fontsize=10)
    axes[0][1].set_title("tracking error (reference - measured)", fontsize=10)
    axes[0][0].legend(loc="best", fontsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("simulated time [s]", fontsize=8)
    figure.suptitle(_title(data, source), fontsize=11)
    # Fixed margins [in]: constrained layout would cost more than drawing the lines.
    height_in = height / DPI
    figure.subplots_adjust(
        left=0.85 / WIDTH_IN,
        right=1.0 - 0.15 / WIDTH_IN,
        bottom=0.5 / height_in,
        top=1.0 - (TITLE_IN - 0.05) / height_in,
        wspace=0.17,
        hspace=0.12,
    )
    try:
        figure.savefig(path, dpi=DPI)
    except OSError as exc:
        raise RecordingError(f"cannot write the plot {path}: {exc.strerror or exc}") from None


def _short(joint: str, arm: str) -> str:
    return joint[len(arm) + 1 :] if joint.startswith(f"{arm}_") else joint


def _title(data: TrackingData, source: str) -> str:
    model = f" ({data.model})" if data.model else ""
    commands = len(data.command_times_s)
    head = f"{data.arm}{model}: position_controller tracking" + (f" - {source}" if source else "")
    if not data.joint_names:
        return head
    worst_joint = _short(data.joint_names[data.worst_joint], data.arm)
    prismatic = data.prismatic[data.worst_joint]
    worst = data.worst_error * 1e3
    unit = "mm" if prismatic else "mrad"
    rms = data.rms_error * 1e3
    return (
        f"{head}\nmax |error| {worst:.3g} {unit} ({worst_joint} at t={data.worst_time_s:.3f} s), "
        f"rms {rms:.3g} {unit}; {commands} command(s) (dotted); {data.samples} samples"
    )
