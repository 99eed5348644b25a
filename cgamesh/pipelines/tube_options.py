"""How centrelines become tubes: the options of a centreline run (the command line's real-data options)."""

from __future__ import annotations

from dataclasses import dataclass

from cgamesh.inputs.formats import InputKind
from cgamesh.options import for_input


@dataclass(frozen=True)
class TubeOptions:
    """How centrelines become tubes (the command line's real-data options), as the centreline
    pipeline receives them; ``from_options`` builds one from the table of options (cgamesh.options),
    whose defaults are these.

    radius:     a constant radius for every node (required when the input has no radii; it
                replaces the file's radii when given).
    min_radius: radii below it are raised to it (a radius of 0 is an error without it).
    up:         which axis of the input points up: x, y or z.
    around:     vertices around every tube and sphere (>= 3).
    subdivide:  rings between consecutive nodes (>= 0); or ``tolerance``, a largest distance
                from the true surface in the input's units, instead.
    color_by:   none | radius | direction | segment | the name of a per-point scalar.
    split:      one mesh per chain or streamline (and one for the spheres) instead of one mesh.
    watertight: one closed 2-manifold mesh (capped tubes, spheres and soma united).
    caps:       close every tube's ends with flat discs (implied by ``watertight``).
    strict:     a chain that cannot be meshed is an error instead of being skipped.
    """

    radius: float | None = None
    min_radius: float | None = None
    up: str = "z"
    around: int = 8
    subdivide: int = 3
    tolerance: float | None = None
    color_by: str = "none"
    split: bool = False
    watertight: bool = False
    strict: bool = False
    caps: bool = False

    @classmethod
    def from_options(cls, values) -> "TubeOptions":
        """The options of ``values`` (a mapping by the table's names) that a centreline input
        takes and were given; the defaults for the others. ``units`` is the reader's, not ours."""
        return cls(**{name: value for name, value in for_input(values, InputKind.CENTERLINES).items()
                      if name != "units"})
