"""The state of a graph of Python objects, saved once and put back in place many times.

:class:`ObjectState` walks everything reachable from a root (attributes, slots, the items
of lists, dicts, sets and deques; not through functions and bound methods: a subscriber's
own objects are not the world's) and keeps a shallow copy of each object's contents: a
dict of its attributes, the items of a container, a copy of a numpy array.
:meth:`ObjectState.restore` writes those contents back into the *same* objects, so every
reference held anywhere (a handle, a subscriber, a compiled kernel bound to an array's
memory) stays valid; objects made since are no longer referenced from the graph, and
objects changed since are as they were.

What Python cannot see is handled by type:

- Ruckig's ``InputParameter`` (compiled, no ``__dict__``): its fields are saved and set back;
- Pinocchio's ``Data`` (a cache of the last kinematics): replaced by a copy of the saved one;
- objects that keep state in compiled code of their own (a Ruckig stepper, a jerk-limited
  trajectory's solver) implement ``on_restored()``, called after every restore, which
  puts that state in one fixed form (:class:`Restorable`);
- caches of what never changes (built on first use, e.g. an arm's self-contact scene)
  are named by their class in ``snapshot_caches``: a restore leaves them as they are, so
  that they are not built again in every episode;
- stateless or constant compiled objects (Pinocchio ``Model``, Ruckig's solver, the fleet
  kernel) are left as they are;
- anything else that is compiled, or has no ``__dict__``, makes :class:`ObjectState`
  raise :class:`UnsavedState` naming its type and where it was found, so that nothing is
  silently left out.

Numbers, strings, enums, classes, modules and functions' code are values, not state;
threads, locks and queues are skipped (they belong to running machinery, not to the
world's state), as are the objects the caller names in ``keep``.
"""

from __future__ import annotations

import collections
import copy
import enum
import types
from collections.abc import Iterable
from typing import Any, Protocol, runtime_checkable

import numpy as np

from armfleet.errors import ArmfleetError

#: Values: never changed in place, nothing to save.
_VALUES: tuple[type, ...] = (
    int,
    float,
    complex,
    str,
    bytes,
    bool,
    type(None),
    type,
    types.ModuleType,
    types.BuiltinFunctionType,
    types.CodeType,
    range,
    slice,
    enum.Enum,
    np.dtype,
    np.generic,
)
#: Modules of running machinery: threads, locks, queues, futures, logging.
_MACHINERY = frozenset(
    {"threading", "_thread", "queue", "_queue", "concurrent.futures._base", "logging"}
)
#: Modules of the metaclasses of classes written in Python (others are compiled bindings).
_PYTHON_METACLASSES = frozenset({"builtins", "abc", "typing", "enum"})
_CONTAINERS = (list, dict, set, collections.deque)
#: Compiled types whose contents never change after they are made, or whose hidden
#: state their owner's ``on_restored`` resets.
_CONSTANT = frozenset(
    {
        "pinocchio.pinocchio_pywrap_default.Model",
        "ruckig.Ruckig",
        "ruckig.OutputParameter",
        "ruckig.Trajectory",
        "armfleet.controllers._fleet_kernel.ReferenceStepper",
        "armfleet.controllers._fleet_kernel.FleetKernel",
        "armfleet.controllers._fleet_kernel.SceneCheck",
    }
)
#: Compiled types restored field by field.
_FIELDS = frozenset({"ruckig.InputParameter"})
#: Compiled types restored by a copy of the saved one.
_COPIED = frozenset({"pinocchio.pinocchio_pywrap_default.Data"})


class UnsavedState(ArmfleetError):
    """An object whose state cannot be saved (compiled, no ``__dict__``, not known here)."""

    def __init__(self, kind: str, path: str) -> None:
        self.kind, self.path = kind, path
        super().__init__(
            f"cannot save the state of a {kind} (at {path}): it keeps its state in "
            f"compiled code; known compiled types: {sorted(_CONSTANT | _FIELDS | _COPIED)}"
        )


@runtime_checkable
class Restorable(Protocol):
    """An object with state the walk cannot see, put in one fixed form after a restore."""

    def on_restored(self) -> None:
        """Called after every restore, once the saved Python state is back."""


def type_name(obj: object) -> str:
    kind = type(obj)
    return f"{kind.__module__}.{kind.__qualname__}"


class ObjectState:
    """The saved contents of every object reachable from ``root`` (module docstring).

    Args:
        root: where the walk starts.
        keep: objects left as they are, and not walked into.
        keep_attributes: attribute names of ``root`` left as they are.

    Raises:
        UnsavedState: an object whose state is out of Python's reach.
    """

    def __init__(
        self, root: object, keep: Iterable[object] = (), keep_attributes: Iterable[str] = ()
    ) -> None:
        self._root = root
        self._keep_attributes = frozenset(keep_attributes)
        #: Each object's attributes, their saved values, and the names left as they are.
        self._attributes: list[tuple[dict[str, Any], dict[str, Any], frozenset[str]]] = []
        self._slots: list[tuple[object, list[tuple[str, Any]]]] = []
        self._lists: list[tuple[list[Any], list[Any]]] = []
        self._dicts: list[tuple[dict[Any, Any], dict[Any, Any]]] = []
        self._sets: list[tuple[set[Any], set[Any]]] = []
        self._deques: list[tuple[collections.deque[Any], list[Any]]] = []
        self._arrays: list[tuple[np.ndarray[Any, Any], np.ndarray[Any, Any]]] = []
        self._fields: list[tuple[object, list[tuple[str, Any]]]] = []
        #: Compiled objects replaced by a copy at each restore: original -> saved copy.
        self._copied: dict[int, tuple[object, object]] = {}
        self._hooks: list[Restorable] = []
        self._walk(root, {id(obj) for obj in keep})
        copied = self._copied
        #: The saved dicts and lists that refer to a copied object (swapped at each restore).
        self._swapping = {
            id(saved)
            for saved in [s for _, s, _ in self._attributes] + [s for _, s in self._dicts]
            if any(id(value) in copied for value in saved.values())
        } | {id(saved) for _, saved in self._lists if any(id(v) in copied for v in saved)}

    @property
    def object_count(self) -> int:
        """Objects whose contents were saved."""
        return (
            len(self._attributes) + len(self._slots) + len(self._lists) + len(self._dicts)
            + len(self._sets) + len(self._deques) + len(self._arrays) + len(self._fields)
            + len(self._copied)
        )  # fmt: skip

    # -- saving -------------------------------------------------------------------------
    def _walk(self, root: object, skip: set[int]) -> None:
        seen = set(skip)
        stack: list[tuple[object, str]] = [(root, "root")]
        while stack:
            obj, path = stack.pop()
            if isinstance(obj, _VALUES) or id(obj) in seen:
                continue
            seen.add(id(obj))
            for child, where in self._save(obj, path):
                stack.append((child, where))

    def _save(self, obj: object, path: str) -> list[tuple[object, str]]:
        """Save ``obj``'s contents; returns what it refers to, to walk next."""
        kind = type(obj)
        if kind.__module__ in _MACHINERY:
            return []
        if isinstance(obj, np.ndarray):
            if obj.flags.writeable:
                self._arrays.append((obj, obj.copy()))
            return []
        if isinstance(obj, tuple | frozenset):
            return [(item, f"{path}[]") for item in obj]
        if isinstance(obj, types.FunctionType | types.MethodType):
            return []  # a callback: what it refers to is the world's only if reached otherwise
        if type(kind).__module__ not in _PYTHON_METACLASSES:  # compiled: by its type
            return self._save_compiled(obj, path)
        children: list[tuple[object, str]] = []
        if isinstance(obj, list):
            self._lists.append((obj, list(obj)))
            children += [(item, f"{path}[]") for item in obj]
        elif isinstance(obj, dict):
            self._dicts.append((obj, dict(obj)))
            children += [(value, f"{path}[{key!r}]") for key, value in obj.items()]
            children += [(key, f"{path}.<key>") for key in obj]
        elif isinstance(obj, set):
            self._sets.append((obj, set(obj)))
            children += [(item, f"{path}{{}}") for item in obj]
        elif isinstance(obj, collections.deque):
            self._deques.append((obj, list(obj)))
            children += [(item, f"{path}[]") for item in obj]
        attributes = getattr(obj, "__dict__", None)
        if isinstance(attributes, dict):
            kept = _caches(obj) | (self._keep_attributes if obj is self._root else _NONE)
            own = {k: v for k, v in attributes.items() if k not in kept}
            self._attributes.append((attributes, own, kept))
            children += [(value, f"{path}.{name}") for name, value in own.items()]
            if isinstance(obj, Restorable):
                self._hooks.append(obj)
        slots = _slot_values(obj)
        if slots:
            self._slots.append((obj, slots))
            children += [(value, f"{path}.{name}") for name, value in slots if value is not _UNSET]
        if attributes is None and not slots and not isinstance(obj, _CONTAINERS):
            raise UnsavedState(type_name(obj), path)  # a C type of Python's or numpy's own
        return children

    def _save_compiled(self, obj: object, path: str) -> list[tuple[object, str]]:
        name = type_name(obj)
        if name in _FIELDS:
            self._fields.append((obj, _fields(obj)))
        elif name in _COPIED:
            self._copied[id(obj)] = (obj, copy.copy(obj))
        elif name not in _CONSTANT:
            raise UnsavedState(name, path)
        return []

    # -- restoring ----------------------------------------------------------------------
    def restore(self) -> None:
        """Put every saved object's contents back (the module docstring says how)."""
        fresh = {key: copy.copy(saved) for key, (_, saved) in self._copied.items()}
        swapping = self._swapping
        for attributes, saved, kept in self._attributes:
            values = _swapped(saved, fresh) if id(saved) in swapping else saved
            now = {k: attributes[k] for k in kept if k in attributes} if kept else None
            attributes.clear()
            attributes.update(values)
            if now:
                attributes.update(now)
        for obj, slot_values in self._slots:
            for name, value in slot_values:
                if value is _UNSET:
                    if hasattr(obj, name):
                        delattr(obj, name)
                else:
                    object.__setattr__(obj, name, fresh.get(id(value), value))
        for items, saved_items in self._lists:
            swap = id(saved_items) in swapping
            items[:] = [fresh.get(id(v), v) for v in saved_items] if swap else saved_items
        for mapping, saved_mapping in self._dicts:
            mapping.clear()
            swap = id(saved_mapping) in swapping
            mapping.update(_swapped(saved_mapping, fresh) if swap else saved_mapping)
        for members, saved_members in self._sets:
            members.clear()
            members.update(saved_members)
        for queue, saved_queue in self._deques:
            queue.clear()
            queue.extend(saved_queue)
        for array, saved_array in self._arrays:
            np.copyto(array, saved_array)
        for obj, fields in self._fields:
            for name, value in fields:
                setattr(obj, name, value)  # a compiled field copies what it is set to
        for hook in self._hooks:
            hook.on_restored()


class _Unset:
    def __repr__(self) -> str:
        return "<unset>"


_UNSET = _Unset()


def _slot_values(obj: object) -> list[tuple[str, Any]]:
    names: list[str] = []
    for klass in type(obj).__mro__:
        slots = klass.__dict__.get("__slots__", ())
        names += [slots] if isinstance(slots, str) else list(slots)
    return [
        (name, getattr(obj, name, _UNSET))
        for name in names
        if name not in ("__dict__", "__weakref__")
    ]


def _caches(obj: object) -> frozenset[str]:
    """The attributes ``obj``'s class names in ``snapshot_caches``."""
    names = getattr(type(obj), "snapshot_caches", None)
    return frozenset(names) if isinstance(names, frozenset | tuple | set | list) else _NONE


_NONE: frozenset[str] = frozenset()


def _fields(obj: object) -> list[tuple[str, Any]]:
    """The settable properties of a compiled object, with copies of their values."""
    fields = []
    for name in dir(type(obj)):
        descriptor = getattr(type(obj), name, None)
        if name.startswith("_") or not isinstance(descriptor, property):
            continue
        if descriptor.fset is None:
            continue
        fields.append((name, copy.copy(getattr(obj, name))))
    return fields


def _swapped(saved: dict[Any, Any], fresh: dict[int, object]) -> dict[Any, Any]:
    return {key: fresh.get(id(value), value) for key, value in saved.items()}
