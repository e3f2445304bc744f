"""Bad spec files: whatever the bytes of a launch spec (or of a controller parameter file
it names), reading it is one line naming the file, the line where known and what would
be valid, exit code 2 from ``armfleet launch --check``, and never a traceback.

Each case goes through the Python loader (:func:`armfleet.load_spec`) and through the
CLI in a subprocess. The bounds checked are those of :mod:`armfleet.checks.located_yaml`
(1 MB, 32 levels, 100,000 values after aliases); the files are built well past them.
"""

from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from armfleet.checks.located_yaml import MAX_DEPTH, MAX_DOCUMENT_BYTES, MAX_NODES
from armfleet.spec import SpecError, load_spec, parse_spec

ARMFLEET = (sys.executable, "-m", "armfleet.cli.main")
TIMEOUT_S = 120.0
BOB = "arms:\n  - name: bob\n    model: panda\n"


@dataclass(frozen=True)
class BadSpec:
    """A spec file's bytes (and those of a controller file next to it, if any), the line
    the error must name (0: the whole file) and what the message must say."""

    content: bytes
    line: int
    expected: tuple[str, ...]
    controller_file: bytes | None = None


def nested(depth: int) -> bytes:
    return ("arms: " + "[" * depth + "]" * depth + "\n").encode()


def alias_chain(links: int) -> bytes:
    """Each anchor a list holding the previous one: shallow text, deep value."""
    lines = ["a0: &a0 [1]"] + [f"a{i}: &a{i} [*a{i - 1}]" for i in range(1, links)]
    return ("\n".join(lines) + "\n").encode()


def billion_laughs() -> bytes:
    """Nine levels of nine aliases each: 9^9 (387 million) values from ~700 bytes."""
    lines = ['lol0: &lol0 "lol"']
    for i in range(1, 10):
        lines.append(f"lol{i}: &lol{i} [" + ", ".join([f"*lol{i - 1}"] * 9) + "]")
    return ("\n".join(lines) + "\narms: *lol9\n").encode()


def merge_bomb() -> bytes:
    """Merge keys doubling a mapping 40 times (2^40 key-value pairs once flattened)."""
    lines = ["m0: &m0 {x: 1, y: 2}"] + [
        f"m{i}: &m{i} {{<<: [*m{i - 1}, *m{i - 1}]}}" for i in range(1, 41)
    ]
    return ("\n".join(lines) + "\n").encode()


BAD_SPECS = [
    pytest.param(
        BadSpec(nested(10_000), 1, (f"nested more than {MAX_DEPTH} levels deep",)),
        id="10,000 nested brackets -> nesting limit, no RecursionError",
    ),
    pytest.param(
        BadSpec(
            b"arms:\n" + b"".join(b"  " * i + b"a:\n" for i in range(1, 200)),
            MAX_DEPTH + 1,
            (f"nested more than {MAX_DEPTH} levels deep",),
        ),
        id="200 nested mappings by indentation -> nesting limit at its line",
    ),
    pytest.param(
        BadSpec(alias_chain(2_000), MAX_DEPTH + 1, (f"more than {MAX_DEPTH} levels deep",)),
        id="aliases nesting 2,000 deep in shallow text -> nesting limit",
    ),
    pytest.param(
        BadSpec(
            BOB.replace("bob", "b\udcffob").encode("utf-8", "surrogateescape"),
            2,
            ("not UTF-8 text (byte 0xff at offset 17)", "save it as UTF-8"),
        ),
        id="a Latin-1 byte in a name -> not UTF-8, byte and offset named",
    ),
    pytest.param(
        BadSpec(BOB.encode("utf-16"), 0, ("UTF-16 text", "save it as UTF-8")),
        id="UTF-16 with byte-order mark -> UTF-16 named, save as UTF-8",
    ),
    pytest.param(
        BadSpec(BOB.encode("utf-16-le"), 1, ("NUL byte at offset 1", "save it as UTF-8")),
        id="UTF-16 without byte-order mark -> NUL byte named",
    ),
    pytest.param(
        BadSpec(BOB.encode("utf-32"), 0, ("UTF-32 text", "save it as UTF-8")),
        id="UTF-32 -> UTF-32 named, save as UTF-8",
    ),
    pytest.param(
        BadSpec(
            b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR" + bytes(range(256)),
            1,
            ("not UTF-8 text (byte 0x89 at offset 0)",),
        ),
        id="a PNG image -> not UTF-8 text",
    ),
    pytest.param(
        BadSpec((BOB + "# " + "x" * MAX_DOCUMENT_BYTES + "\n").encode(), 0, ("larger than 1 MB",)),
        id="a spec over 1 MB (a huge comment) -> size limit, not read",
    ),
    pytest.param(
        # lol6 (line 7) is the first over the limit: 9^6 = 531,441 strings.
        BadSpec(billion_laughs(), 7, (f"expands to more than {MAX_NODES:,} values",)),
        id="billion laughs -> expansion limit",
    ),
    pytest.param(
        # m_i holds 3 + 2 m_(i-1) values, m0 5: m14 (line 15) is the first over, 131,069.
        BadSpec(merge_bomb(), 15, (f"expands to more than {MAX_NODES:,} values",)),
        id="merge-key bomb -> expansion limit before flattening",
    ),
    pytest.param(
        BadSpec(b"arms: &a [*a]\n", 1, ("a value cannot contain itself",)),
        id="an alias inside itself -> refused",
    ),
    pytest.param(
        BadSpec(b"- name: bob\n  model: panda\n", 1, ("expected a mapping (key: value)",)),
        id="top level a list -> a mapping expected",
    ),
    pytest.param(
        BadSpec(b"just some text\n", 1, ("expected a mapping (key: value)",)),
        id="top level a scalar -> a mapping expected",
    ),
    pytest.param(
        BadSpec((BOB + "arms: []\n").encode(), 4, ("key 'arms' appears twice",)),
        id="a key twice -> duplicate named at its line",
    ),
    pytest.param(
        BadSpec(b"arms:\n\t- name: bob\n", 2, ("not valid YAML",)),
        id="tab indentation -> not valid YAML at its line",
    ),
    pytest.param(
        BadSpec((BOB + "---\n" + BOB).encode(), 4, ("not valid YAML", "another document")),
        id="two documents -> not valid YAML",
    ),
    pytest.param(
        BadSpec(
            b'arms: !!python/object/apply:os.system ["true"]\n',
            1,
            ("could not determine a constructor",),
        ),
        id="a python object tag -> refused, nothing run",
    ),
    pytest.param(
        BadSpec(
            ("world:\n  dt_s: 1" + "0" * 5000 + "\n").encode(),
            2,
            ("cannot read", "value has 5001 digits"),
        ),
        id="a 5,000-digit number -> refused at its line, value cut short",
    ),
    pytest.param(
        BadSpec(
            ("arms:\n  - name: bob\n    model: " + "m" * 500_000 + "\n").encode(),
            3,
            ("arms[0].model:", "(500002 characters) is longer than 4096 characters"),
        ),
        id="a 500,000-character model name -> refused, echoed cut short",
    ),
    pytest.param(
        BadSpec(
            ("world:\n  realtime: " + "y" * 500_000 + "\n").encode(),
            2,
            ("world.realtime: expected true or false, got 'yyy", "(500002 characters)"),
        ),
        id="a 500,000-character switch value -> refused, echoed cut short",
    ),
    pytest.param(
        BadSpec(b"world:\n  dt_s: 2001-02-30\n", 2, ("cannot read '2001-02-30'",)),
        id="an impossible date -> refused at its line",
    ),
    pytest.param(
        BadSpec(
            (BOB + "    controllers:\n      position_controller: {file: mine.yaml}\n").encode(),
            4,
            ("arms[0].controllers:", "mine.yaml", "UTF-16 text", "save it as UTF-8"),
            controller_file="position_controller:\n  kp_s2: 900\n".encode("utf-16"),
        ),
        id="a UTF-16 controller file -> the spec's line and the file named",
    ),
    pytest.param(
        BadSpec(
            (BOB + "    controllers:\n      position_controller: {file: mine.yaml}\n").encode(),
            4,
            ("arms[0].controllers:", "mine.yaml", f"nested more than {MAX_DEPTH} levels"),
            controller_file=b"position_controller: " + b"[" * 5000 + b"]" * 5000 + b"\n",
        ),
        id="a controller file nested 5,000 deep -> nesting limit, file named",
    ),
]


def write_case(folder: Path, case: BadSpec) -> Path:
    spec = folder / "cell.yaml"
    spec.write_bytes(case.content)
    if case.controller_file is not None:
        (folder / "mine.yaml").write_bytes(case.controller_file)
    return spec


def check_message(message: str, spec: Path, case: BadSpec) -> None:
    assert "\n" not in message.strip()
    assert len(message) < len(str(spec)) + 300  # no echo of a huge value
    assert "Traceback" not in message
    where = f"{spec}:{case.line}: " if case.line else f"{spec}: "
    assert where in message, message
    for text in case.expected:
        assert text in message, message


@pytest.mark.parametrize("case", BAD_SPECS)
def test_bad_spec_file_from_python_is_one_spec_error(tmp_path: Path, case: BadSpec) -> None:
    spec = write_case(tmp_path, case)
    with pytest.raises(SpecError) as raised:
        load_spec(spec)
    check_message(str(raised.value), spec, case)


@pytest.mark.parametrize("case", BAD_SPECS)
def test_bad_spec_file_from_the_cli_is_one_line_exit_2(tmp_path: Path, case: BadSpec) -> None:
    spec = write_case(tmp_path, case)
    result = subprocess.run(
        [*ARMFLEET, "launch", str(spec), "--check"],
        capture_output=True, text=True, timeout=TIMEOUT_S,
        env=os.environ | {"XDG_RUNTIME_DIR": str(tmp_path)},
    )  # fmt: skip
    assert result.returncode == 2, result.stderr
    assert result.stdout == ""
    assert result.stderr.startswith("armfleet: error: ")
    check_message(result.stderr, spec, case)


@pytest.mark.parametrize("case", BAD_SPECS)
def test_bad_spec_bytes_through_parse_spec_are_the_same_error(case: BadSpec) -> None:
    """The Python API's parse_spec follows the same rules for text given as bytes (PyYAML
    alone would decode a UTF-16 byte-order mark instead of refusing it)."""
    if case.controller_file is not None:
        pytest.skip("the controller file is read from disk")
    with pytest.raises(SpecError) as raised:
        parse_spec(case.content, "cell.yaml", base_dir=Path("/specs"))
    check_message(str(raised.value), Path("cell.yaml"), case)


def test_what_stays_valid_within_the_bounds(tmp_path: Path) -> None:
    """A UTF-8 byte-order mark, anchors shared between arms and a merge key are fine: the
    bounds refuse attacks, not YAML's ordinary features."""
    spec = tmp_path / "cell.yaml"
    text = (
        "arms:\n"
        "  - &bob {name: bob, model: panda, controllers: &slow {position_controller:\n"
        "      {parameters: {velocity_scaling: 0.5}}}}\n"
        "  - {<<: *bob, name: toby, at_m: [1, 0]}\n"
        "  - {name: ann, model: panda, at_m: [2, 0], controllers: *slow}\n"
    )
    spec.write_bytes(b"\xef\xbb\xbf" + text.encode())
    arms = load_spec(spec).arms
    assert [arm.name for arm in arms] == ["bob", "toby", "ann"]
    assert [arm.pose.x for arm in arms] == [0.0, 1.0, 2.0]
    for arm in arms:
        assert arm.controllers["position_controller"].parameters == {"velocity_scaling": 0.5}


def test_nesting_up_to_the_limit_reads(tmp_path: Path) -> None:
    """The limit is where it says: 32 levels read (and then fail as a spec, at a field)."""
    spec = tmp_path / "cell.yaml"
    spec.write_bytes(nested(MAX_DEPTH - 1))  # the top-level mapping is the first level
    with pytest.raises(SpecError, match=r"arms\[0\]: expected a mapping"):
        load_spec(spec)
