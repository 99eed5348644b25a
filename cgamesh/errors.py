"""One exception tree for every error cgamesh reports to a user.

The command line turns any ``CgameshError`` into one line on stderr and exit code 2;
anything else escaping is a bug.
"""

from __future__ import annotations


class CgameshError(Exception):
    """Base of every error cgamesh raises on purpose."""


class InvalidInputError(CgameshError, ValueError):
    """The input (a scene file, an argument, a control object) is not valid."""


class NonFiniteInputError(InvalidInputError):
    """A NaN or an infinity where a finite number is required."""


class DegenerateGeometryError(InvalidInputError):
    """Geometry that has no meaning: a zero radius, collinear points, a vanishing projection."""


class SceneFileError(InvalidInputError):
    """A scene file that does not follow the format; the message names file, line and key path."""


class ExportError(CgameshError):
    """An output file could not be written."""
