"""Argument types shared by the commands: each checks a value and says what it expected."""

from __future__ import annotations

import argparse


def whole_number(minimum: int):
    """An argparse type accepting whole numbers >= ``minimum``."""
    from cgamesh.options import WholeNumber

    return argument_type(WholeNumber(minimum).parse)


def positive_number(text: str) -> float:
    """An argparse type accepting finite numbers > 0."""
    from cgamesh.options import PositiveNumber

    return argument_type(PositiveNumber().parse)(text)


def argument_type(parse):
    """``parse`` (text -> value, ValueError saying what was expected) as an argparse type, so
    argparse prints that message: ``argument --around: expected a whole number >= 2, got 1``."""

    def checked(text: str):
        try:
            return parse(text)
        except ValueError as error:
            raise argparse.ArgumentTypeError(str(error)) from None

    return checked


def add_option_flags(parser: argparse.ArgumentParser, names: tuple[str, ...] | None = None) -> tuple[str, ...]:
    """One flag per option of the table in cgamesh.options (or of those ``names``), in a --help
    section per group; returns their names (argparse dests, the table's names). A value not
    given is None (a switch: False), which the table reads as "not given"."""
    from cgamesh.inputs.formats import InputKind, suffixes
    from cgamesh.options import OPTIONS, Choice, Group

    chosen = [option for option in OPTIONS if names is None or option.name in names]
    titles = {Group.MESHING: Group.MESHING.value,
              Group.CENTERLINES: f"{Group.CENTERLINES.value} ({', '.join(suffixes(InputKind.CENTERLINES))})"}
    groups = {group: parser.add_argument_group(title) for group, title in titles.items()
              if any(option.group is group for option in chosen)}
    for option in chosen:
        group = groups[option.group]
        if option.is_switch:
            group.add_argument(option.flag, dest=option.name, action="store_true", help=option.help)
        elif isinstance(option.value, Choice):
            group.add_argument(option.flag, dest=option.name, choices=option.value.choices, help=option.help)
        else:
            group.add_argument(option.flag, dest=option.name, type=argument_type(option.value.parse),
                               metavar=option.metavar, help=option.help)
    return tuple(option.name for option in chosen)


def option_values(args: argparse.Namespace) -> dict:
    """The table's options that ``args`` gives (cgamesh.options.given), by name."""
    from cgamesh.options import BY_NAME, given

    return given({name: getattr(args, name) for name in BY_NAME if hasattr(args, name)})


def memory_size(text: str) -> int:
    """An argparse type for --max-memory: a size such as 2G, 512MiB or 1e9 (bytes)."""
    from cgamesh.budget import parse_size

    try:
        return parse_size(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def add_budget_option(parser: argparse.ArgumentParser) -> None:
    """--max-memory (cgamesh.budget): the most memory a run may ask for."""
    from cgamesh.budget import DEFAULT_FRACTION

    parser.add_argument("--max-memory", type=memory_size, metavar="SIZE",
                        help=f"refuse (or stream) work needing more memory than this, e.g. 2G or 512MiB "
                             f"(default {DEFAULT_FRACTION:g} of the memory available)")


def finite_number(text: str) -> float:
    """An argparse type accepting finite numbers (a NaN threshold would silently judge nothing)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not abs(value) < float("inf"):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text}")
    return value
