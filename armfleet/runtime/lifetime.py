"""Whether a handle may still be used: its world open, its arm still in the world.

A :class:`armfleet.World` owns one :class:`Lifetime`, ended by ``close()``; each
arm gets a child of it, ended when the arm is removed. Handles (an
:class:`~armfleet.Arm`, its :class:`~armfleet.Gripper`, the world's
:class:`~armfleet.frames.tf_tree.TfTree`) hold the lifetime of what they stand for, and
every method or property that reads or commands it is wrapped in
:func:`while_alive`: after ``world.close()`` it raises
:class:`~armfleet.errors.WorldClosed`, after ``world.remove(arm)``
:class:`~armfleet.errors.UnknownArm` (also once an arm of the same name is back:
a handle stands for one arm, not for a name). What a handle *is* (name, model,
joint names and limits) stays readable.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Concatenate, ParamSpec, Protocol, TypeVar

from armfleet.errors import ArmfleetError

P = ParamSpec("P")
R = TypeVar("R")


class Lifetime:
    """Alive until :meth:`end` is called on it or on its parent.

    Args:
        ended: the error to raise once it has ended (called then, so that it can
            list what exists at that time).
        parent: the lifetime this one cannot outlive (an arm's: its world's).
    """

    def __init__(self, ended: Callable[[], ArmfleetError], parent: Lifetime | None = None) -> None:
        self._error = ended
        self._parent = parent
        self._ended = False

    @property
    def alive(self) -> bool:
        return not self._ended and (self._parent is None or self._parent.alive)

    def end(self) -> None:
        """End it (idempotent); children end with it."""
        self._ended = True

    def check(self) -> None:
        """Raise the error of the outermost ended lifetime (a closed world before a
        removed arm), or return."""
        if self._parent is not None:
            self._parent.check()
        if self._ended:
            raise self._error()


class Living(Protocol):
    """Anything with a :class:`Lifetime`."""

    @property
    def lifetime(self) -> Lifetime: ...


S = TypeVar("S", bound=Living)


def while_alive(method: Callable[Concatenate[S, P], R]) -> Callable[Concatenate[S, P], R]:
    """Wrap ``method`` so that it first checks its handle's lifetime."""

    @functools.wraps(method)
    def checked(self: S, /, *args: P.args, **kwargs: P.kwargs) -> R:
        self.lifetime.check()
        return method(self, *args, **kwargs)

    return checked
