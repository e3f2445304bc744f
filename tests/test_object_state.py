"""ObjectState: a graph of Python objects put back in place, what it leaves alone, and
what it refuses to save."""

from __future__ import annotations

import numpy as np
import pytest

from armfleet.world.object_state import ObjectState, UnsavedState


class Node:
    """A plain object with state of every kind."""

    def __init__(self) -> None:
        self.count = 0
        self.items: list[object] = [1, 2]
        self.table: dict[str, object] = {"a": 1}
        self.seen: set[int] = {1}
        self.values = np.zeros(3)
        self.child: Node | None = None
        self.restored = 0

    def on_restored(self) -> None:
        self.restored += 1


class Cached(Node):
    snapshot_caches = frozenset({"cache"})

    def __init__(self) -> None:
        super().__init__()
        self.cache: list[int] | None = None


def test_a_restore_puts_every_content_back_into_the_same_objects() -> None:
    root = Node()
    root.child = Node()
    child, items, values = root.child, root.items, root.values
    state = ObjectState(root)
    root.count = 5
    root.items.append(3)
    root.table["b"] = 2
    root.seen.add(9)
    root.values[:] = 7.0
    root.child.count = 4
    root.child = Node()  # replaced: the old one comes back, as it was
    root.extra = "made after the save"  # type: ignore[attr-defined]
    state.restore()
    assert root.child is child and root.items is items and root.values is values
    assert (root.count, root.items, root.table, root.seen) == (0, [1, 2], {"a": 1}, {1})
    assert np.array_equal(values, np.zeros(3)) and child.count == 0
    assert not hasattr(root, "extra")
    assert (root.restored, child.restored) == (1, 1)  # each one's hook, after the restore


def test_caches_named_by_the_class_and_kept_objects_are_left_as_they_are() -> None:
    root = Cached()
    machinery = Node()
    root.child = machinery
    state = ObjectState(root, keep=[machinery])
    root.cache = [1, 2, 3]  # built on first use, after the save
    machinery.count = 8
    root.count = 3
    state.restore()
    assert root.cache == [1, 2, 3] and machinery.count == 8 and root.count == 0


def test_a_callbacks_own_objects_are_not_the_graphs() -> None:
    root = Node()
    heard: list[int] = []
    root.table["callback"] = lambda: heard.append(1)
    state = ObjectState(root)
    heard += [1, 2]
    state.restore()
    assert heard == [1, 2]


def test_state_out_of_pythons_reach_is_refused_naming_its_type_and_place() -> None:
    root = Node()
    root.table["rng"] = np.random.default_rng(0)  # a compiled generator, no __dict__
    with pytest.raises(UnsavedState, match=r"numpy\.random\._generator\.Generator \(at root") as e:
        ObjectState(root)
    assert "root.table['rng']" in str(e.value) and "\n" not in str(e.value)
