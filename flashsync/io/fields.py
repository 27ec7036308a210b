"""Typed, checked access to the objects of a JSON (or YAML) file being read.

Every value is checked for its type (a JSON ``"false"`` is text, not a boolean; ``"1"`` is
not a number), finiteness, shape and order; a bad one is one error line naming the file,
where in it, the field and what is wrong.
"""

from __future__ import annotations

import math
import types
import typing
from typing import NoReturn

import numpy as np

from flashsync.errors import InputError

#: Whole numbers are stored as 64-bit integers: their magnitude stays below this.
_WHOLE_LIMIT = 2**63


def describe(value: object) -> str:
    """A JSON value as the reader of an error line sees it: ``the text "false"``, ``the
    number 1``, ``null``, ``a list``, ..."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return f"the number {value!r}".replace("nan", "NaN").replace("inf", "Infinity")
    if isinstance(value, str):
        shown = value if len(value) <= 40 else value[:37] + "..."
        return f'the text "{shown}"'
    if isinstance(value, (list, tuple)):
        return f"a list of {len(value)}"
    if isinstance(value, dict):
        return "an object"
    return f"a {type(value).__name__}"


def is_number(value: object) -> bool:
    """A JSON number (int or float, not a boolean)."""
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))


class Fields:
    """One JSON object of a file being read, with checked access to its fields.

    Parameters
    ----------
    data : object
        The parsed value; it must be an object (dict).
    source : str
        The file, named first in errors.
    where : str
        Where the object is in the file (``camera "cam2"``), named next; empty for the top.
    error : type
        The error raised (an :class:`~flashsync.errors.InputError` or a subclass).
    fix : str
        What to do, ending each error line.
    """

    def __init__(self, data: object, source: str, where: str = "", error: type = InputError, fix: str = "fix the file"):
        self.source, self.where, self.error, self.fix = source, where, error, fix
        if not isinstance(data, dict):
            self._raise(f"{where or 'the file'} is {describe(data)}, expected an object {{...}}")
        self.data = data

    def _raise(self, problem: str) -> NoReturn:
        raise self.error(f"{self.source}: {problem}; {self.fix}")

    def fail(self, name: str, problem: str) -> NoReturn:
        """Raise the error about field ``name``: ``FILE: WHERE: "name" PROBLEM; FIX``."""
        where = f"{self.where}: " if self.where else ""
        self._raise(f'{where}"{name}" {problem}')

    def has(self, name: str) -> bool:
        return name in self.data

    def value(self, name: str) -> object:
        """The raw value of a field that must be present."""
        if name not in self.data:
            self.fail(name, "is missing")
        return self.data[name]

    def text(self, name: str, nonempty: bool = True) -> str:
        value = self.value(name)
        if not isinstance(value, str) or (nonempty and not value):
            self.fail(name, f"is {describe(value)}, expected {'a non-empty' if nonempty else 'a'} text")
        return value

    def boolean(self, name: str) -> bool:
        value = self.value(name)
        if not isinstance(value, bool):
            self.fail(name, f"is {describe(value)}, expected true or false (no quotes)")
        return value

    def integer(self, name: str, minimum: int | None = None) -> int:
        value = self.value(name)
        if not is_number(value) or not math.isfinite(value) or value != int(value):
            self.fail(name, f"is {describe(value)}, expected a whole number (no quotes)")
        if minimum is not None and value < minimum:
            self.fail(name, f"is {value}, expected at least {minimum}")
        if abs(value) >= _WHOLE_LIMIT:
            self.fail(name, f"is {value}, expected a whole number below 2**63")
        return int(value)

    def number(self, name: str, minimum: float | None = None, positive: bool = False, optional: bool = False):
        """A finite number (``optional``: or null, returned as None)."""
        value = self.value(name)
        if value is None and optional:
            return None
        if not is_number(value):
            self.fail(name, f"is {describe(value)}, expected a number (no quotes){' or null' if optional else ''}")
        if not math.isfinite(value):
            self.fail(name, f"is {describe(value)}, expected a finite number")
        if positive and not value > 0:
            self.fail(name, f"is {value!r}, expected a positive number")
        if minimum is not None and value < minimum:
            self.fail(name, f"is {value!r}, expected at least {minimum}")
        return float(value)

    def numbers(
        self,
        name: str,
        length: int | None = None,
        minimum_length: int = 0,
        increasing: bool = False,
        minimum: float | None = None,
    ) -> np.ndarray:
        """A list of finite numbers as a float64 array of shape (n,)."""
        value = self.value(name)
        if not isinstance(value, list):
            self.fail(name, f"is {describe(value)}, expected a list of numbers")
        for index, item in enumerate(value):
            if not is_number(item) or not math.isfinite(item):
                self.fail(name, f"[{index}] is {describe(item)}, expected a finite number")
        array = np.asarray(value, dtype=np.float64)
        if length is not None and len(array) != length:
            self.fail(name, f"has {len(array)} values, expected {length}")
        if len(array) < minimum_length:
            self.fail(name, f"has {len(array)} values, expected at least {minimum_length}")
        if increasing and np.any(np.diff(array) <= 0):
            index = int(np.argmax(np.diff(array) <= 0)) + 1
            self.fail(
                name,
                f"is not increasing at [{index}] ({float(array[index - 1])!r} then {float(array[index])!r}), "
                "expected ever larger values",
            )
        if minimum is not None and np.any(array < minimum):
            index = int(np.argmax(array < minimum))
            self.fail(name, f"[{index}] is {float(array[index])!r}, expected at least {minimum}")
        return array

    def matrix(self, name: str, shape: tuple[int, int]) -> np.ndarray:
        """A list of ``shape[0]`` lists of ``shape[1]`` finite numbers, float64."""
        value = self.value(name)
        if not isinstance(value, list) or len(value) != shape[0] or not all(isinstance(r, list) for r in value):
            self.fail(name, f"is {describe(value)}, expected {shape[0]} rows of {shape[1]} numbers")
        for i, row in enumerate(value):
            if len(row) != shape[1]:
                self.fail(name, f"row {i} has {len(row)} values, expected {shape[1]} ({shape[0]}x{shape[1]})")
            for j, item in enumerate(row):
                if not is_number(item) or not math.isfinite(item):
                    self.fail(name, f"[{i}][{j}] is {describe(item)}, expected a finite number")
        return np.asarray(value, dtype=np.float64)

    def objects(self, name: str, where: str) -> list[Fields]:
        """A list of objects; ``where`` names each by its index (``"camera {}"``)."""
        value = self.value(name)
        if not isinstance(value, list):
            self.fail(name, f"is {describe(value)}, expected a list of objects")
        return [
            Fields(item, self.source, where.format(index), self.error, self.fix) for index, item in enumerate(value)
        ]


def check_types(
    cls: type, data: dict, where: str, source: str, skip: tuple[str, ...] = (), fix: str = "fix the scenario"
) -> None:
    """Each value of ``data`` has the type of its field of dataclass ``cls``: ``str``,
    ``bool`` (true/false, not text), ``int`` (whole, not a boolean), ``float`` (a finite
    number), ``X | None``; ``tuple`` fields are lists of finite numbers or of lists of them.
    Fields in ``skip`` and of other types are not checked. An error names ``source``,
    ``where`` and the field, and ends with ``fix``."""
    hints = typing.get_type_hints(cls)
    for key, value in data.items():
        if key in skip or key not in hints:
            continue
        problem = _type_problem(value, hints[key])
        if problem:
            raise InputError(f"{source}: {where}: '{key}' is {describe(value)}, expected {problem}; {fix}")


def _type_problem(value: object, hint: object) -> str | None:
    """What ``value`` should have been for type ``hint``, or None if it is one."""
    options = typing.get_args(hint) if isinstance(hint, types.UnionType) else (hint,)
    if value is None and type(None) in options:
        return None
    wanted = [option for option in options if option is not type(None)]
    problems = []
    for option in wanted:
        origin = typing.get_origin(option) or option
        if origin is bool:
            if isinstance(value, bool):
                return None
            problems.append("true or false (no quotes)")
        elif origin is int:
            if is_number(value) and not isinstance(value, float):
                return None
            problems.append("a whole number (no quotes)")
        elif origin is float:
            if is_number(value) and math.isfinite(value):
                return None
            problems.append("a finite number (no quotes)")
        elif origin is str:
            if isinstance(value, str):
                return None
            problems.append("a text")
        elif origin is tuple:
            if _numbers_nested(value):
                return None
            problems.append("a list of numbers (or of lists of numbers)")
        else:
            return None
    if type(None) in options:
        problems.append("null")
    return " or ".join(problems)


def _numbers_nested(value: object, depth: int = 2) -> bool:
    """A list of finite numbers, or of such lists (``depth`` levels)."""
    if not isinstance(value, (list, tuple)):
        return False
    return all(
        (is_number(item) and math.isfinite(item)) or (depth > 1 and _numbers_nested(item, depth - 1)) for item in value
    )
