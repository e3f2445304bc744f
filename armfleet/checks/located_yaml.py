"""Safe YAML loading that remembers the line of every mapping and key.

Validation errors then point at ``file:line``, as a compiler would.

A YAML file is input from anyone, so the loader bounds what it will read before
building anything from it (one rule for every YAML file armfleet reads: launch
specs and controller parameter files, from the Python API, the CLI and ``--check``):

* at most :data:`MAX_DOCUMENT_BYTES` of UTF-8 text (a UTF-8 byte-order mark is
  allowed; UTF-16/32 and other encodings are refused with the offending byte);
* nesting at most :data:`MAX_DEPTH` levels deep, counted through aliases too
  (10,000 nested brackets would otherwise exhaust Python's recursion limit);
* at most :data:`MAX_NODES` values once anchors and aliases are expanded (the
  "billion laughs" document holds a few hundred bytes and 10^9 values), and no
  alias that contains itself;
* values a constructor cannot build (an integer of 5,000 digits, the date
  2001-02-30) are errors at their line, not exceptions from deep inside PyYAML.

Every such problem is a :class:`YamlDocumentError` carrying the line and the problem.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import yaml

from armfleet.errors import ArmfleetError, shown_name

#: Largest YAML file read [bytes]; a 400-arm spec written out in full is ~60 kB.
MAX_DOCUMENT_BYTES = 1_000_000
#: Deepest nesting of mappings and lists (a launch spec needs 7).
MAX_DEPTH = 32
#: Most values (scalars, mappings, lists) once aliases are expanded.
MAX_NODES = 100_000

_BYTE_ORDER_MARKS = (  # UTF-32 first: its little-endian mark starts with UTF-16's
    (b"\xff\xfe\x00\x00", "UTF-32"),
    (b"\x00\x00\xfe\xff", "UTF-32"),
    (b"\xff\xfe", "UTF-16"),
    (b"\xfe\xff", "UTF-16"),
)


class YamlDocumentError(ArmfleetError):
    """A YAML file that cannot be read as a document.

    Attributes:
        source: the file (or what the text came from).
        line: 1-based line of the problem (0 if it concerns the whole file).
        problem: what is wrong and what would be right, e.g. ``not UTF-8 text (byte
            0xff at offset 3); save it as UTF-8``.
    """

    def __init__(self, source: str, line: int, problem: str) -> None:
        self.source, self.line, self.problem = source, line, problem
        where = f"{source}:{line}" if line else source
        super().__init__(f"{where}: {problem}")


class LocatedDict(dict[str, Any]):
    """A mapping from YAML with the 1-based line of itself and of each key."""

    line: int = 0
    key_lines: dict[str, int]

    def line_of(self, key: str) -> int:
        return self.key_lines.get(key, self.line)


class LocatedList(list[Any]):
    """A sequence from YAML with the 1-based line of itself and of each item."""

    line: int = 0
    item_lines: list[int]

    def line_of(self, index: int) -> int:
        return self.item_lines[index] if index < len(self.item_lines) else self.line


#: libyaml's parser when PyYAML was built with it (about 10x faster), else the Python one.
_SAFE_LOADER: type[yaml.SafeLoader] = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


_MERGE_TAG = "tag:yaml.org,2002:merge"


class _LocatingLoader(_SAFE_LOADER):  # type: ignore[misc,valid-type]
    """A safe loader (no arbitrary objects) whose mappings and sequences know their lines."""


# YAML 1.1 (PyYAML) reads an exponent without a dot, ``1e-5``, as text; YAML 1.2, Python
# and the error messages that print such bounds (``[1e-05, 0.002]``) read a number.
_LocatingLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?[0-9][0-9_]*(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"),
    list("-+0123456789"),
)


def _construct_mapping(loader: _LocatingLoader, node: yaml.MappingNode) -> LocatedDict:
    written = sum(1 for key_node, _ in node.value if key_node.tag != _MERGE_TAG)
    loader.flatten_mapping(node)  # merged pairs first, then the written ones
    merged = len(node.value) - written
    result = LocatedDict()
    result.line = node.start_mark.line + 1
    result.key_lines = {}
    seen: set[str] = set()
    for index, (key_node, value_node) in enumerate(node.value):
        key = loader.construct_object(key_node, deep=True)
        if not isinstance(key, str):
            raise yaml.constructor.ConstructorError(
                None, None, f"keys must be text, got {key!r}", key_node.start_mark
            )
        if index >= merged:  # a written key overrides a merged one, but not another written
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f"key '{key}' appears twice", key_node.start_mark
                )
            seen.add(key)
        result[key] = loader.construct_object(value_node, deep=True)
        result.key_lines[key] = key_node.start_mark.line + 1
    return result


def _construct_sequence(loader: _LocatingLoader, node: yaml.SequenceNode) -> LocatedList:
    result = LocatedList(loader.construct_object(child, deep=True) for child in node.value)
    result.line = node.start_mark.line + 1
    result.item_lines = [child.start_mark.line + 1 for child in node.value]
    return result


def _at_its_line(
    construct: Callable[[Any, yaml.Node], Any],
) -> Callable[[_LocatingLoader, yaml.Node], Any]:
    """``construct`` with a value it cannot build (ValueError, OverflowError) reported at
    the value's line, like any other YAML error."""

    def guarded(loader: _LocatingLoader, node: yaml.Node) -> Any:
        try:
            return construct(loader, node)
        except (ValueError, OverflowError) as exc:
            reason = str(exc).split(";")[0]  # not Python's advice to raise its own limit
            raise yaml.constructor.ConstructorError(
                None, None, f"cannot read {shown_name(node.value)} ({reason})", node.start_mark
            ) from None

    return guarded


_LocatingLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping)
_LocatingLoader.add_constructor(
    yaml.resolver.BaseResolver.DEFAULT_SEQUENCE_TAG, _construct_sequence
)
for _tag in ("int", "float", "timestamp", "binary"):
    _full_tag = f"tag:yaml.org,2002:{_tag}"
    _LocatingLoader.add_constructor(
        _full_tag, _at_its_line(yaml.constructor.SafeConstructor.yaml_constructors[_full_tag])
    )


def read_located(path: Path, source: str | None = None) -> Any:
    """Read the YAML file at ``path`` within the bounds above (see :func:`load_located`).

    Raises:
        YamlDocumentError: the file cannot be read, is too large, is not UTF-8 text, or
            is not a YAML document within the bounds.
    """
    name = str(path) if source is None else source
    try:
        with path.open("rb") as stream:
            data = stream.read(MAX_DOCUMENT_BYTES + 1)  # no more: the size is checked
    except OSError as exc:
        raise YamlDocumentError(name, 0, f"cannot be read ({exc.strerror})") from None
    return load_located(data, name)


def decode_utf8(data: bytes, source: str) -> str:
    """``data`` as UTF-8 text (a leading byte-order mark dropped).

    Raises:
        YamlDocumentError: naming the encoding found or the first byte that is not UTF-8.
    """
    for mark, encoding in _BYTE_ORDER_MARKS:
        if data.startswith(mark):
            raise YamlDocumentError(
                source, 0, f"{encoding} text (it starts with a {encoding} byte-order mark); "
                "save it as UTF-8",
            )  # fmt: skip
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise YamlDocumentError(
            source, line, f"not UTF-8 text (byte 0x{data[exc.start]:02x} at offset "
            f"{exc.start}); save it as UTF-8",
        ) from None  # fmt: skip
    if "\x00" in text:
        offset = data.index(b"\x00")
        raise YamlDocumentError(
            source, data[:offset].count(b"\n") + 1, f"holds a NUL byte at offset {offset} "
            "(UTF-16 without a byte-order mark, or not text at all); save it as UTF-8 text",
        )  # fmt: skip
    return text


def load_located(text: str | bytes, source: str = "<text>") -> Any:
    """Parse YAML ``text``; mappings become :class:`LocatedDict`, sequences :class:`LocatedList`.

    Bytes must be UTF-8 (:func:`decode_utf8`), as a file's must: PyYAML would otherwise
    guess UTF-16 from a byte-order mark.

    Raises:
        YamlDocumentError: ``text`` is not one YAML document within the bounds of this
            module (too large, too deep, too many values once aliases are expanded, an
            alias inside itself, a value that cannot be built, or a syntax error), at its line.
    """
    if len(text) > MAX_DOCUMENT_BYTES:  # bytes, or characters of text already decoded
        raise YamlDocumentError(source, 0, f"larger than {_size(MAX_DOCUMENT_BYTES)}; a YAML "
                                "file armfleet reads holds at most that")  # fmt: skip
    if isinstance(text, bytes):
        text = decode_utf8(text, source)
    try:
        _check_nesting(yaml.parse(text, Loader=_LocatingLoader), source)
        loader = _LocatingLoader(text)  # a SafeLoader subclass: no arbitrary objects
        try:
            node = loader.get_single_node()
            if node is None:
                return None
            _check_expansion(node, source)
            return loader.construct_document(node)
        finally:
            loader.dispose()
    except yaml.YAMLError as exc:
        line = _line(getattr(exc, "problem_mark", None))
        problem = " ".join(str(getattr(exc, "problem", None) or exc).split())
        if "nesting depth" in problem:  # PyYAML >= 6.0.4 stops deep nesting as it scans
            raise _too_deep(source, line) from None
        raise YamlDocumentError(source, line, f"not valid YAML: {problem}") from None


def _check_nesting(events: Iterator[yaml.Event], source: str) -> None:
    """Refuse nesting deeper than MAX_DEPTH before anything recursive sees the document."""
    depth = 0
    for event in events:
        if isinstance(event, yaml.CollectionStartEvent):
            depth += 1
            if depth > MAX_DEPTH:
                raise _too_deep(source, _line(event.start_mark))
        elif isinstance(event, yaml.CollectionEndEvent):
            depth -= 1


def _check_expansion(root: yaml.Node, source: str) -> None:
    """Refuse a node graph that aliases make too deep, too large or cyclic.

    Iterative, and each node is measured once however many aliases point at it, so
    the check itself costs time in the size of the text, not of the expansion.
    """
    size: dict[int, int] = {}  # id(node) -> values in its expansion (capped)
    depth: dict[int, int] = {}
    open_nodes: set[int] = set()  # expansion started, not finished: the current path
    stack: list[tuple[yaml.Node, bool]] = [(root, False)]
    while stack:
        node, finished = stack.pop()
        key = id(node)
        children = _children(node)
        if finished:
            open_nodes.discard(key)
            size[key] = min(MAX_NODES + 1, 1 + sum(size[id(c)] for c in children))
            depth[key] = 1 + max((depth[id(c)] for c in children), default=0)
            if size[key] > MAX_NODES:
                raise YamlDocumentError(
                    source, node.start_mark.line + 1, f"expands to more than {MAX_NODES:,} "
                    "values (anchors and aliases included); write the values out instead",
                )  # fmt: skip
            if depth[key] > MAX_DEPTH + 1:
                raise _too_deep(source, node.start_mark.line + 1)
            continue
        if key in size:
            continue
        open_nodes.add(key)
        stack.append((node, True))
        for child in children:
            if id(child) in open_nodes:
                raise YamlDocumentError(
                    source, child.start_mark.line + 1, "an alias refers to the mapping or "
                    "list that contains it; a value cannot contain itself",
                )  # fmt: skip
            if id(child) not in size:
                stack.append((child, False))


def _line(mark: Any) -> int:
    """The 1-based line of a PyYAML mark (0 without one)."""
    return mark.line + 1 if mark is not None else 0


def _children(node: yaml.Node) -> list[yaml.Node]:
    if isinstance(node, yaml.MappingNode):
        return [part for pair in node.value for part in pair]
    if isinstance(node, yaml.SequenceNode):
        return list(node.value)
    return []


def _too_deep(source: str, line: int) -> YamlDocumentError:
    return YamlDocumentError(
        source, line, f"nested more than {MAX_DEPTH} levels deep; a launch spec or parameter "
        "file needs fewer than 10",
    )  # fmt: skip


def _size(count: int) -> str:
    return f"{count / 1e6:g} MB"
