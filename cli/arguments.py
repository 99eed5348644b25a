"""Argument types shared by the commands: each checks a value and says what it expected."""

from __future__ import annotations

import argparse


def whole_number(minimum: int):
    """An argparse type accepting whole numbers >= ``minimum``."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"expected a whole number >= {minimum}, got {value}")
        return value

    return parse


def positive_number(text: str) -> float:
    """An argparse type accepting finite numbers > 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not 0.0 < value < float("inf"):
        raise argparse.ArgumentTypeError(f"expected a finite number > 0, got {text}")
    return value


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
