"""The YAML subset that scene files are written in, read as JSON (the fast path's first pass).

The subset: one block mapping at the top; block mappings and lists of identifier keys
(``- - x`` for a list in a list); plain numbers, names and the YAML 1.2 core words (true,
false, null); one-line flow lists and mappings of numbers; comments. A line at a time would
cost a Python step per line, which PyYAML's block layout (a number per line) multiplies by
five, so the pieces most often written are matched whole by one regular expression: a
block list of numbers with its key, and a list item that is a block mapping of numbers
and flow lists (a control as PyYAML writes it). The block structure becomes JSON text with
the line of every list item's mapping under the key "" and a JSON reader builds it
(``json_reader``).

Anything outside the subset (quotes, anchors, aliases, tags, block scalars, tabs, multi-line
flow, non-ASCII, a misplaced line, ...) gives None: the careful reader
(``cgamesh.inputs.scene``) then decides. Numbers are matched by a loose class where that is
cheaper; JSON's number grammar is the subset's (``_NUMBER``), so anything else makes the
JSON invalid, which gives None too.
"""

from __future__ import annotations

import json
import re
from functools import partial


class OutsideSubset(Exception):
    """The text or a value is one the fast path does not vouch for."""


# A comment starts at '#' at the start of a line or after a space (in the subset no quoted
# text can hold one).
_COMMENT = re.compile(r"(?<![^ \n])#[^\n]*")
# The keys of flow mappings after the first: ', ' then an identifier (a number in a list
# starts with a digit or '-'). Every key ends in ': ' or ':' at the line end.
_NEXT_KEY = re.compile(r", (?=[A-Za-z_])")
_INNER_COLON = re.compile(r":(?![ \n])")

_NUMBER = r"-?(?:0|[1-9][0-9]*)(?:\.[0-9]+)?(?:[eE][-+]?[0-9]+)?"
_IDENTIFIER = r"[A-Za-z_][A-Za-z0-9_]*"
# One-line flow collections, nested at most three deep (a mapping of lists of lists, as
# `through` needs), holding only numbers and (quoted) keys: the whole value must be one
# collection, so that '[1], [2]' is not read as two. Possessive: no backtracking.
_FLOW_ATOM = r'(?:[-+0-9.eE, ]++|"[A-Za-z_][A-Za-z0-9_]*: )'
_FLAT_LIST = rf"\[{_FLOW_ATOM}*+\]"
_NESTED_LIST = rf"\[(?:{_FLOW_ATOM}|{_FLAT_LIST})*+\]"
_FLOW = rf"\[(?:{_FLOW_ATOM}|{_FLAT_LIST})*+\]|\{{(?:{_FLOW_ATOM}|{_NESTED_LIST})*+\}}"
# A block list of numbers under a key, one per line (as PyYAML's block style writes every
# list): matched with its key as one piece, so that its lines cost no Python work each. The
# items are numerals by this loose class; the JSON reader then enforces the exact grammar (which
# is _NUMBER's), so anything else makes the JSON invalid and the file falls back.
_NUMERAL = r"[-+.0-9eE]++"
_RUN = rf"\n(?P<run_indent> *)- {_NUMERAL} *+(?:\n(?P=run_indent)- {_NUMERAL} *+)*+"
# A list item that is a block mapping of numbers and flow lists (a control as PyYAML writes
# it), matched whole: '- key: value' then its other keys two columns in, each with a value
# on its line or a block list of numbers at the key's column (PyYAML's indentless layout).
# The next line that is not blank must not be deeper than the dash, or the mapping goes on
# in a shape this piece does not take (the lines are then read one by one).
_ITEM_VALUE = rf"(?::(?: +(?:{_FLOW}|{_NUMERAL}) *+|(?:\n(?P=item_indent)  - {_NUMERAL} *+)++))"
_ITEM = (rf"(?P<item_indent> *+)- (?P<item>{_IDENTIFIER}{_ITEM_VALUE}"
         rf"(?:\n(?P=item_indent)  {_IDENTIFIER}{_ITEM_VALUE})*+)"
         rf"(?!(?:\n *+$)*+\n(?P=item_indent) )")
# indent, the dashes ('- ', or '- - ' for a list in a list), key, then a flow value, a number,
# a name, a run (only after a key with nothing after it), or anything else (outside the subset).
_LINE = re.compile(rf'^(?:{_ITEM}|( *+)((?:- +)+)?(?:(?P<key>{_IDENTIFIER}):(?: +|$))?'
                   rf'(?:({_FLOW})|({_NUMBER})|({_IDENTIFIER})|(?(key)({_RUN})|(?!))|([^\n]+))? *)$',
                   re.M)
# YAML 1.2 core-schema words (the careful reader's resolution) as JSON literals.
_WORDS = {word: literal for literal, words in (("true", ("true", "True", "TRUE")),
                                               ("false", ("false", "False", "FALSE")),
                                               ("null", ("null", "Null", "NULL")))
          for word in words}


def _no_constant(name: str):
    raise OutsideSubset(name)  # NaN / Infinity: JSON's words, not YAML's


def json_reader(prefer_orjson: bool = True):
    """The JSON reader of the fast path: orjson's (the ``fastread`` extra: it builds the data
    in about a third of json's time) when installed, else the standard library's. Both refuse
    NaN and infinities and read every number of the subset to the same value, so the fast
    path gives the same scene with either (the tests read every text with both). They differ
    only on an integer past 64 bits, a float to orjson and an int to json: where a number is
    due the checks read both as float(int), where an integer is due both are refused."""
    if prefer_orjson:
        try:
            from orjson import loads
        except ImportError:
            pass
        else:
            return loads
    return partial(json.loads, parse_constant=_no_constant)


_read_json = json_reader()


def plain_document(text: str) -> tuple[dict, int] | None:
    """(the document as plain data, every mapping that is a list item holding its 1-based line
    under the key "", the number of keys written in it); None outside the subset. A repeated
    key leaves the mapping with fewer keys than were written: the checks count every key they
    see and step aside on a difference (cheaper than a hook on every mapping)."""
    text = _keys_quoted(text)
    if text is None:
        return None
    try:
        document = "".join(_json_pieces(_LINE.findall(text))).replace(": ", '": ')
        # In the subset every ':' ends a key (a ':' in a plain scalar was refused, comments
        # are gone, and any other place of ': ' makes the line or the JSON invalid).
        keys = text.count(":")
        return _read_json(document), keys
    except (OutsideSubset, ValueError, RecursionError):
        return None


_PRINTABLE = bytes(range(0x20, 0x7F)) + b"\n"


def _keys_quoted(text: str) -> str | None:
    """The text without comments, the quotes of its flow keys opened; None if it cannot be in
    the subset."""
    # Printable ASCII and line feeds only: no tab (YAML's indentation rules for it are
    # subtle), no carriage return, no byte PyYAML refuses, no Unicode line break (NEL, U+2028)
    # that would shift line numbers; no quote, as the keys are quoted here.
    if not text.isascii() or text.encode("ascii").translate(None, _PRINTABLE) or '"' in text:
        return None
    if "#" in text:
        text = _COMMENT.sub("", text)
    # Open the quotes of the keys of flow mappings: a '"' before the first key and before the
    # keys after ', '; their ': ' closes them (``plain_document``, in one pass). In the subset
    # ':' appears only after keys (PyYAML reads a ':' followed by anything else as part of a
    # plain scalar), so a stray quote only makes the JSON invalid.
    if not text.endswith("\n"):
        text += "\n"
    if _INNER_COLON.search(text):
        return None  # a ':' inside a plain scalar
    return _NEXT_KEY.sub(', "', text.replace("{", '{"'))


def _json_pieces(lines: list[tuple[str, ...]]) -> list[str]:
    """JSON text of the block structure; each piece is (item indent, item, indent, dashes,
    key, flow, number, name, run, run indent, other) as ``_LINE`` splits it (a line, a key
    with its block list of numbers, or a whole block-mapping list item). Raises OutsideSubset
    for anything the subset leaves out. The keys of flow mappings are left as ``"key: `` (the
    caller closes their quotes in one pass over the whole text).

    The innermost open block collection is (``mapping``, ``column``, ``items``): a mapping's
    column is that of its keys, a list's that of its dashes, ``items`` whether it has one yet
    (for the commas); ``outer`` holds the enclosing ones. ``pending`` is the column of a
    mapping whose last key had no value on its line (a nested block follows, or null)."""
    out: list[str] = []
    append = out.append
    outer: list[tuple[bool, int, bool]] = []
    mapping, column_open, items = True, -1, False  # column -1: the document is not open yet
    pending = -1
    number = later = 0
    pads: dict[str, str] = {}  # '\n' and the column of a block item's keys, by the dash's indent
    for item_indent, item, indent, dash, key, flow, numeral, name, run, run_indent, other in lines:
        number += 1 + later  # later: the lines of the last piece after its first
        later = 0
        if item:
            # A whole block mapping as a list item: as a flow mapping on the dash's line.
            later = item.count("\n")
            if ":\n" in item:
                flow = _item_mapping(item, item_indent)
            else:  # values on their lines only (PyYAML's mixed layout): the common case inline
                keys = pads.get(item_indent) or pads.setdefault(item_indent,
                                                                "\n" + item_indent + "  ")
                flow = '{"' + item.replace(keys, ', "') + "}"
            indent, dash = item_indent, "- "
        if (flow and dash == "- " and not (key or mapping) and items and pending < 0
                and len(indent) == column_open):
            # The next item of the open list, a flow collection (a control): likewise.
            append(f',{{"":{number},{flow[1:]}' if flow[0] == "{" else "," + flow)
            continue
        if key and items and mapping and not dash and pending < 0 and len(indent) == column_open:
            # The most common line, a key of the open mapping after its first: what the
            # general steps below do for it, without the tests that cannot apply.
            if flow or numeral:
                append(f',"{key}":{flow or numeral}')
            elif name:
                append(f',"{key}":' + (_WORDS.get(name) or f'"{name}"'))
            elif run:
                if len(run_indent) < column_open:
                    raise OutsideSubset(number)
                append(f',"{key}":[{run.replace(run[:len(run_indent) + 3], ",")[1:]}]')
                later = run.count("\n")
            elif other:
                raise OutsideSubset(number)
            else:
                append(f',"{key}":')
                pending = column_open
            continue
        if other:
            raise OutsideSubset(number)
        if not (dash or key):
            if flow or numeral or name:
                raise OutsideSubset(number)  # a value alone on its line: a continuation
            continue  # blank or comment
        column = len(indent)
        if pending >= 0:
            if column > pending or (dash and column == pending):
                outer.append((mapping, column_open, True))
                mapping, column_open, items = not dash, column, False
                append("[" if dash else "{")
            else:
                append("null")
            pending = -1
        while column_open > column or (column_open == column and not mapping and not dash):
            append("}" if mapping else "]")  # a list at a key's column ends there too
            mapping, column_open, items = outer.pop()
        if column_open < 0:
            if out or dash or column:
                raise OutsideSubset(number)  # the document is not one block mapping
            append("{")
            mapping, column_open = True, 0
        elif column_open != column or mapping == bool(dash):
            raise OutsideSubset(number)  # misplaced line
        if items:
            append(",")
        items = True
        if dash:
            if len(dash) > 3 and dash.count("-") > 1:
                # '- - x': each dash after the first opens a list, the item of the one before,
                # at the dash's column.
                for inner in _DASHES.findall(dash)[:-1]:
                    column += len(inner)
                    dash = dash[len(inner):]
                    outer.append((mapping, column_open, True))
                    mapping, column_open = False, column
                    append("[")
            if not key:
                if flow:
                    # A flow mapping as a list item: its line goes in first.
                    append(f'{{"":{number},{flow[1:]}' if flow[0] == "{" else flow)
                elif numeral:
                    append(numeral)
                elif name and name not in _WORDS:
                    append(f'"{name}"')
                else:
                    # '-' alone, or a boolean or null as a list item: never valid in a scene.
                    raise OutsideSubset(number)
                continue
            outer.append((mapping, column_open, True))
            mapping, column_open = True, column + len(dash)
            append(f'{{"":{number},"{key}":')
        else:
            append(f'"{key}":')
        if flow:
            append(flow)
        elif numeral:
            append(numeral)
        elif name:
            append(_WORDS.get(name) or f'"{name}"')
        elif run:
            # A block list of numbers on the lines after the key, indented at least as far
            # as the key (else the list is not the key's value: the careful reader decides).
            if len(run_indent) < column_open:
                raise OutsideSubset(number)
            append(f'[{run.replace(run[:len(run_indent) + 3], ",")[1:]}]')
            later = run.count("\n")
        else:
            pending = column_open
    if column_open < 0:
        raise OutsideSubset("an empty document")
    if pending >= 0:
        append("null")
    append("}" if mapping else "]")
    out.extend("}" if frame[0] else "]" for frame in reversed(outer))
    return out


_DASHES = re.compile(r"- +")


def _item_mapping(item: str, indent: str) -> str:
    """The flow mapping (keys' quotes opened, as ``_keys_quoted`` leaves them) of a list
    item's block mapping as ``_ITEM`` matched it, ``indent`` the dash's."""
    keys = "\n" + indent + "  "
    if ":\n" not in item:
        return '{"' + item.replace(keys, ', "') + "}"
    # Block lists of numbers: their items become ',x' after the key's ':'.
    pieces = item.replace(keys + "- ", ",").split(keys)
    return '{"' + ', "'.join([piece.replace(":,", '":[', 1) + "]" if ":," in piece else piece
                             for piece in pieces]) + "}"
