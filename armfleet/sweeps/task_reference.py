"""A sweep's task, named as ``module:function`` or ``file.py[:function]``, found in a worker.

A task is ``task(world, rng, **parameters) -> dict of metrics``. A file named without a
function (``file.py``, or ``file.py:`` with nothing after the colon) means its function
``task``, or, when it has none, the one public function it defines. A task in a file is
sent to the workers as its text, so a cluster's machines need not share a folder with
this one; a task in a module must be importable on every worker (as armfleet's are).
"""

from __future__ import annotations

import hashlib
import importlib
import inspect
import sys
import types
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from armfleet.checks.user_paths import file_problem

#: The default function of a task file named without ``:function`` (a file without one
#: that defines exactly one public function means that one).
DEFAULT_FUNCTION = "task"

Task = Callable[..., Any]


class TaskError(ValueError):
    """A task that cannot be found or called as a task; the message says why."""


@dataclass(frozen=True)
class TaskReference:
    """Where a task lives.

    Attributes:
        name: as written (``module:function`` or ``path.py:function``).
        module: the module to import, or None for a file.
        function: the function's name in it.
        path: the file, for a task in a file.
        source: the file's text, for a task in a file.
        by_default: a file named without a function: :attr:`function` is
            :data:`DEFAULT_FUNCTION`, or the file's only public function if it has no
            such one.
    """

    name: str
    module: str | None
    function: str
    path: str | None = None
    source: str | None = None
    by_default: bool = False

    def load(self) -> Task:
        """The task function (imports its module or runs its file once per process).

        Raises:
            TaskError: no such module, file or function, or not a function.
        """
        if self.module is not None:
            try:
                module = importlib.import_module(self.module)
            except ImportError as exc:
                raise TaskError(f"cannot import {self.module!r}: {exc}") from None
        else:
            module = _file_module(self.path or "", self.source or "")
        task = getattr(module, self.function, None)
        if task is None:
            functions = _public_functions(module)
            if self.by_default and len(functions) == 1:
                return self._checked(getattr(module, functions[0]))
            if self.by_default:
                raise TaskError(
                    f"{self.name}: no function {self.function!r} in it, and not one function "
                    f"to take instead (it defines {', '.join(functions) or 'none'}); name "
                    f"one as {self.name.rstrip(':')}:function"
                )
            raise TaskError(
                f"{self.name}: no {self.function!r} in it; its functions: "
                f"{', '.join(functions) or 'none'}"
            )
        return self._checked(task)

    def _checked(self, task: object) -> Task:
        if not callable(task) or inspect.isclass(task):
            raise TaskError(
                f"{self.name} is a {type(task).__name__}, not a function "
                "task(world, rng, **parameters) -> dict"
            )
        function: Task = task
        return function


def task_reference(text: str, base_dir: Path | None = None) -> TaskReference:
    """Read ``module:function``, ``file.py`` or ``file.py:function`` (a relative file is
    looked for in ``base_dir`` first, the spec's folder). ``file.py`` and ``file.py:``
    name the file's default task (see :attr:`TaskReference.by_default`).

    Raises:
        TaskError: a name that is neither form, a file that is no regular file, or a
            function name that is not an identifier.
    """
    text = text.strip()
    head, _, function = text.rpartition(":") if ":" in text else (text, "", "")
    if head.endswith(".py") or text.endswith(".py"):
        path_text = head if head.endswith(".py") else text
        # file.py:function; file.py and file.py: (nothing after the colon) take the default
        named = ":" in text and head.endswith(".py") and bool(function.strip())
        function = function.strip() if named else DEFAULT_FUNCTION
        if not function.isidentifier():
            raise TaskError(f"task {text!r}: {function!r} is not a function name")
        path = Path(path_text).expanduser()
        if not path.is_absolute() and base_dir is not None and (base_dir / path).exists():
            path = base_dir / path
        problem = file_problem(path)
        if problem is not None:
            raise TaskError(f"task file {path_text!r} {problem}")
        source = path.read_text()
        return TaskReference(text, None, function, str(path.resolve()), source, not named)
    if not function or not all(part.isidentifier() for part in head.split(".")):
        raise TaskError(
            f"task {text!r}: give module:function (e.g. "
            "armfleet.scenarios.reach:reach) or a file task.py[:function]"
        )
    if not function.isidentifier():
        raise TaskError(f"task {text!r}: {function!r} is not a function name")
    if head.startswith(_MOVED_SCENARIOS):  # the shipped scenarios' room before 0.2
        head = "armfleet.scenarios." + head.removeprefix(_MOVED_SCENARIOS)
    return TaskReference(text, head, function)


#: Where the shipped scenarios lived until they got a room of their own
#: (:mod:`armfleet.scenarios`); sweep files naming them there keep working.
_MOVED_SCENARIOS = "armfleet.sweeps.scenarios."


def task_keywords(task: Task, name: str) -> set[str]:
    """The keyword parameters ``task`` takes after ``(world, rng)``; ``"**"`` among them
    if it takes any keyword.

    Raises:
        TaskError: it cannot be called with a world and a generator.
    """
    try:
        signature = inspect.signature(task)
    except (TypeError, ValueError):
        return {"**"}
    positional = [
        p
        for p in signature.parameters.values()
        if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)
    ]
    varargs = any(p.kind == p.VAR_POSITIONAL for p in signature.parameters.values())
    if len(positional) < 2 and not varargs:
        raise TaskError(f"{name} takes {len(positional)} argument(s); a task takes (world, rng)")
    required = [p for p in positional[2:] if p.default is p.empty]
    if required:
        raise TaskError(
            f"{name}: parameter {required[0].name!r} has no default; give task parameters "
            "defaults (a sweep sets them by keyword)"
        )
    keywords = {p.name for p in positional[2:]}
    for parameter in signature.parameters.values():
        if parameter.kind == parameter.KEYWORD_ONLY:
            keywords.add(parameter.name)
        if parameter.kind == parameter.VAR_KEYWORD:
            keywords.add("**")
    return keywords


def _public_functions(module: types.ModuleType) -> list[str]:
    """The public functions ``module`` defines itself (not those it imports), sorted."""
    return sorted(
        name
        for name, value in vars(module).items()
        if inspect.isfunction(value)
        and not name.startswith("_")
        and value.__module__ == module.__name__
    )


def _file_module(path: str, source: str) -> types.ModuleType:
    """The module of a task file's text, made once per process and text."""
    digest = hashlib.sha256(source.encode()).hexdigest()[:16]
    name = f"armfleet_sweep_task_{digest}"
    if name in sys.modules:
        return sys.modules[name]
    module = types.ModuleType(name)
    module.__file__ = path
    sys.modules[name] = module  # dataclasses defined in it look their module up
    try:
        exec(compile(source, path, "exec"), module.__dict__)
    except Exception as exc:
        del sys.modules[name]
        raise TaskError(f"task file {path}: {type(exc).__name__}: {exc}") from None
    return module
