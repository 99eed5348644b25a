"""The careful scene reader's YAML: core-schema loading and the node-walking ``Reader``.

A scene file is composed into PyYAML's node tree by the YAML 1.2 core schema (``compose``,
``CoreLoader``), and walked by ``Reader``, whose every read names the file, the line of the
node, its key path, what was expected and what was got when the value is wrong.
"""

from __future__ import annotations

import difflib
import math
import re

import yaml

from cgamesh.errors import InvalidInputError, NonFiniteInputError, SceneFileError
from cgamesh.inputs.scene_rules import MAX_LENGTH
from cgamesh.inputs.scene_specs import Location, Vec3

_STR, _NULL, _BOOL, _INT, _FLOAT = (f"tag:yaml.org,2002:{t}"
                                    for t in ("str", "null", "bool", "int", "float"))
# YAML 1.2 core schema. PyYAML resolves by YAML 1.1, where 1e-4 (no dot) is a string and
# yes / on / no are booleans; people writing scene files by hand mean the 1.2 reading.
_CORE_PATTERNS = {
    _NULL: re.compile(r"(?:~|null|Null|NULL|)\Z"),
    _BOOL: re.compile(r"(?:true|True|TRUE|false|False|FALSE)\Z"),
    _INT: re.compile(r"(?:[-+]?[0-9]+|0o[0-7]+|0x[0-9a-fA-F]+)\Z"),
    _FLOAT: re.compile(r"(?:[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)(?:[eE][-+]?[0-9]+)?"
                       r"|[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN))\Z"),
}


class CoreLoader(yaml.SafeLoader):
    """SafeLoader resolving plain scalars by the YAML 1.2 core schema only."""

    # Key None: tried for every plain scalar. The first match wins, so "1" stays an int.
    yaml_implicit_resolvers = {None: [(tag, _CORE_PATTERNS[tag])
                                      for tag in (_NULL, _BOOL, _INT, _FLOAT)]}

    def scan_to_next_token(self) -> None:
        """PyYAML's, also skipping tabs between tokens of a line (YAML 1.2's s-separate-in-line:
        ``[1,<tab>2]`` is valid). A tab in a block line's indentation is still refused."""
        while True:
            super().scan_to_next_token()
            if self.peek() != "\t" or not self._within_line():
                return
            while self.peek() in " \t":
                self.forward()

    def _within_line(self) -> bool:
        """In a flow collection, or past the indentation of the current line."""
        return self.flow_level > 0 or self.buffer[self.pointer - self.column:self.pointer].strip(" ") != ""


def compose(text: str, file: str) -> yaml.Node | None:
    """The document's node tree (None if empty); YAML errors become one-line SceneFileErrors."""
    try:
        return yaml.compose(text, Loader=CoreLoader)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        where = f"{file}:{mark.line + 1}" if mark else file
        problem = exc.problem or exc.context or "syntax error"
        if exc.context and exc.problem and exc.problem.startswith("but "):
            problem = f"{exc.context}, {exc.problem}"  # "expected a single document, but found ..."
        elif exc.context and exc.problem and exc.context_mark:
            problem += f" ({exc.context} on line {exc.context_mark.line + 1})"
        raise SceneFileError(f"{where}: invalid YAML: {' '.join(problem.split())}") from exc
    except yaml.reader.ReaderError as exc:
        line = text.count("\n", 0, exc.position) + 1
        raise SceneFileError(f"{file}:{line}: invalid YAML: character #x{exc.character:04x} is "
                             f"not allowed ({exc.reason})") from exc
    except RecursionError as exc:
        depth, line = _deepest(text)
        raise SceneFileError(f"{file}:{line}: invalid YAML: nested too deeply ({depth} levels of "
                             "lists and mappings)") from exc


def _deepest(text: str) -> tuple[int, int]:
    """(greatest nesting depth, 1-based line where it is first reached) of a YAML text, from its
    parse events: the parser keeps an explicit stack, so this works where composing the node
    tree (recursive) runs out of stack."""
    depth = deepest = 0
    line = 1
    for event in yaml.parse(text, Loader=CoreLoader):
        if isinstance(event, (yaml.SequenceStartEvent, yaml.MappingStartEvent)):
            depth += 1
            if depth > deepest:
                deepest, line = depth, event.start_mark.line + 1
        elif isinstance(event, (yaml.SequenceEndEvent, yaml.MappingEndEvent)):
            depth -= 1
    return deepest, line


def core_value(node: yaml.ScalarNode) -> object:
    """A scalar node's value: str, None, bool, int or float (maybe NaN/inf). ValueError for a
    tag the scene format does not use or a text that does not fit its (explicit) tag."""
    text, tag = node.value, node.tag
    if tag == _STR:
        return text
    if tag not in _CORE_PATTERNS or not _CORE_PATTERNS[tag].match(text):
        raise ValueError(f"{text!r} tagged {tag}")
    if tag == _NULL:
        return None
    if tag == _BOOL:
        return text.lower() == "true"
    if tag == _INT:
        base = {"0o": 8, "0x": 16}.get(text[:2], 10)
        return int(text if base == 10 else text[2:], base)
    lowered = text.lower()
    if lowered.endswith(".inf"):
        return -math.inf if lowered.startswith("-") else math.inf
    return math.nan if lowered == ".nan" else float(text)


def _describe(node: yaml.Node) -> str:
    """What a node holds, for the 'got ...' half of a message."""
    if isinstance(node, yaml.MappingNode):
        return "a mapping"
    if isinstance(node, yaml.SequenceNode):
        n = len(node.value)
        return "an empty list" if n == 0 else f"a list of {n} item{'s' * (n != 1)}"
    try:
        value = core_value(node)
    except ValueError as exc:
        return str(exc)
    if value is None or type(value) is float:
        return "null" if value is None else repr(value)
    if type(value) is bool:
        return f"{str(value).lower()} (a boolean)"
    return f"{value!r} (a string)" if type(value) is str else f"{value} (an integer)"


_NOT_SCALAR = object()


class Reader:
    """Checked values out of one file's nodes: methods take ``(node, key_path, ...)`` and return
    plain Python values; ``error`` / ``wrong`` build the one-line exception for callers to raise."""

    def __init__(self, file: str) -> None:
        self.file = file

    def location(self, node: yaml.Node, path: str) -> Location:
        return Location(self.file, node.start_mark.line + 1, path)

    def error(self, node: yaml.Node, path: str, detail: str,
              kind: type[InvalidInputError] = SceneFileError) -> InvalidInputError:
        """``file:line: key.path <detail>``, e.g. detail = "must be > 0, got 0.0"."""
        where = self.location(node, path)
        return kind(f"{where} {detail}" if path else f"{where}: the scene {detail}")

    def wrong(self, node: yaml.Node, path: str, expected: str) -> InvalidInputError:
        """``... must be <expected>, got <what the node holds>``; NaN / inf anywhere counts as
        a non-finite input rather than a format mistake."""
        got = _describe(node)  # which shows a float as its repr
        kind = NonFiniteInputError if got in ("nan", "inf", "-inf") else SceneFileError
        return self.error(node, path, f"must be {expected}, got {got}", kind)

    def scalar(self, node: yaml.Node, path: str) -> object:
        """The value of a scalar node, ``_NOT_SCALAR`` for a list or mapping."""
        if not isinstance(node, yaml.ScalarNode):
            return _NOT_SCALAR
        try:
            return core_value(node)
        except ValueError as exc:
            raise self.error(node, path, f"must be a plain value, got {exc}") from None

    def mapping(self, node: yaml.Node, path: str,
                allowed: tuple[str, ...] | None = None) -> dict[str, yaml.Node]:
        """key -> value node of a mapping with string keys, each once and (if given) allowed."""
        if not isinstance(node, yaml.MappingNode):
            raise self.wrong(node, path, "a mapping")
        entries: dict[str, yaml.Node] = {}
        first_line: dict[str, int] = {}
        for key_node, value_node in node.value:
            key = self.scalar(key_node, path)
            if type(key) is not str:
                raise self.error(key_node, path, f"must have names as keys, got the key "
                                                 f"{_describe(key_node)}")
            key_path = _join(path, key)
            if key in entries:
                raise self.error(key_node, key_path, f"must appear only once, got it again "
                                                     f"(first on line {first_line[key]})")
            entries[key], first_line[key] = value_node, key_node.start_mark.line + 1
        if allowed is not None:
            self.reject_unknown(node, path, allowed)
        return entries

    def reject_unknown(self, node: yaml.MappingNode, path: str, allowed: tuple[str, ...]) -> None:
        for key_node, _ in node.value:
            if key_node.value not in allowed:
                close = difflib.get_close_matches(key_node.value, allowed, n=1)
                hint = f"; did you mean {close[0]!r}?" if close else ""
                raise self.error(key_node, _join(path, key_node.value),
                                 f"is not a known key; expected one of {', '.join(allowed)}{hint}")

    def require(self, node: yaml.Node, entries: dict, key: str, path: str,
                expected: str) -> yaml.Node:
        """The value node of a required key; missing -> error at the mapping's own line."""
        if key not in entries:
            raise self.error(node, _join(path, key), f"must be given ({expected}), got no such key")
        return entries[key]

    def optional(self, entries: dict, key: str, path: str, default, read, *args):
        """``read(value_node, key_path, *args)`` if the key is there, else ``default``."""
        return read(entries[key], _join(path, key), *args) if key in entries else default

    def sequence(self, node: yaml.Node, path: str, expected: str) -> list[yaml.Node]:
        """The item nodes of a list; ``expected`` describes the list wanted, for the message."""
        if not isinstance(node, yaml.SequenceNode):
            raise self.wrong(node, path, expected)
        return node.value

    def boolean(self, node: yaml.Node, path: str) -> bool:
        value = self.scalar(node, path)
        if type(value) is not bool:
            raise self.wrong(node, path, "true or false")
        return value

    def choice(self, node: yaml.Node, path: str, options: tuple[str, ...]) -> str:
        value = self.scalar(node, path)
        if type(value) is not str or value not in options:
            raise self.wrong(node, path, f"one of {', '.join(options)}")
        return value

    def number(self, node: yaml.Node, path: str) -> float:
        """A finite float; integers are accepted, booleans and quoted text are not."""
        value = self.scalar(node, path)
        if type(value) is int:
            try:
                value = float(value)
            except OverflowError:
                raise self.error(node, path, f"must be a finite number, got an integer of "
                                 f"{len(str(abs(value)))} digits", NonFiniteInputError) from None
        if type(value) is not float:
            raise self.wrong(node, path, "a number")
        if not math.isfinite(value):
            raise self.error(node, path, f"must be a finite number, got {value!r}",
                             NonFiniteInputError)
        return value

    def number_in(self, node: yaml.Node, path: str, low: float, high: float) -> float:
        value = self.number(node, path)
        if not low <= value <= high:
            raise self.error(node, path, f"must be in [{low:g}, {high:g}], got {value!r}")
        return value

    def integer(self, node: yaml.Node, path: str, low: int, high: int) -> int:
        value = self.scalar(node, path)
        if type(value) is not int or not low <= value <= high:
            raise self.wrong(node, path, f"an integer from {low} to {high}")
        return value

    def length(self, node: yaml.Node, path: str) -> float:
        """A finite number of magnitude at most MAX_LENGTH (lengths and coordinates)."""
        value = self.number(node, path)
        if abs(value) > MAX_LENGTH:
            raise self.error(node, path, f"must be within +-{MAX_LENGTH:g} (output files store float32), "
                                         f"got {value!r}")
        return value

    def position(self, node: yaml.Node, path: str) -> Vec3:
        """A point: 3 finite coordinates, each of magnitude at most MAX_LENGTH."""
        items = self.sequence(node, path, "a list of 3 numbers")
        if len(items) != 3:
            raise self.wrong(node, path, "a list of 3 numbers")
        x, y, z = (self.length(item, f"{path}[{i}]") for i, item in enumerate(items))
        return x, y, z

    def vector3(self, node: yaml.Node, path: str) -> Vec3:
        """A list of exactly 3 finite numbers, as a tuple of floats."""
        items = self.sequence(node, path, "a list of 3 numbers")
        if len(items) != 3:
            raise self.wrong(node, path, "a list of 3 numbers")
        x, y, z = (self.number(item, f"{path}[{i}]") for i, item in enumerate(items))
        return x, y, z


def _join(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key
