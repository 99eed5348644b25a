"""The table of meshing options: every option once, and everything else derived from it.

``OPTIONS`` lists each option with its name, how a value is parsed and checked, its default,
its help text, which kinds of input it concerns and what takes it; ``EXCLUSIVE`` lists the
combinations refused. From these come:

- the command line's flags (``cgamesh IN -o OUT`` and ``cgamesh batch``: cgamesh_cli.arguments
  adds one flag per option, ``--min-radius`` for ``min_radius``), and its refusals of an
  option given for an input it does not concern;
- the keywords ``cgamesh.load`` and ``cgamesh.tubes`` accept for each kind (``keywords``), and
  their checks (``check_keywords``);
- the options of ``cgamesh batch`` and ``cgamesh.batch(...)`` (every name here), of which each
  input takes those of its kind;
- the values handed on, each built by its own class from the table (which imports neither the
  pipelines nor the writers): ``Resolution.from_options`` for scenes,
  ``TubeOptions.from_options`` for centrelines, ``GltfOptions.from_options`` for the glTF part of
  the writers' ``WriteOptions``.

An option is "given" when its value is not None (a switch: when it is True), so 0 is a value.

To add an option: one ``Option`` here, and the field it fills in the value its pipeline or
writer receives (docs/architecture.md, "Input formats and options").
"""

from __future__ import annotations

import enum
import math
import numbers
from collections.abc import Mapping
from dataclasses import dataclass

from cgamesh.errors import InvalidInputError
from cgamesh.inputs.formats import InputKind
from cgamesh.inputs.units import METERS_PER_UNIT

SCENE, CENTERLINES = InputKind.SCENE, InputKind.CENTERLINES
BOTH = frozenset({SCENE, CENTERLINES})
UP_AXES = ("x", "y", "z")
COLOR_MODES = ("none", "radius", "direction", "segment")  # or the name of a per-point scalar


class Group(enum.Enum):
    """The command line's --help section an option is listed in."""

    MESHING = "meshing options"
    CENTERLINES = "centreline inputs"


@dataclass(frozen=True)
class WholeNumber:
    """Whole numbers >= ``minimum``."""

    minimum: int

    def parse(self, text: str) -> int:
        """The number ``text`` spells; ValueError saying what was expected."""
        try:
            value = int(text)
        except ValueError:
            raise ValueError(f"expected a whole number, got {text!r}") from None
        if value < self.minimum:
            raise ValueError(f"expected a whole number >= {self.minimum}, got {value}")
        return value

    def check(self, name: str, value) -> None:
        """A value handed over in Python: InvalidInputError naming ``name`` unless it fits."""
        if isinstance(value, bool) or not isinstance(value, numbers.Integral):
            raise InvalidInputError(f"{name} must be a whole number, got {value!r}")
        if value < self.minimum:
            raise InvalidInputError(f"{name} must be >= {self.minimum}, got {value}")


@dataclass(frozen=True)
class PositiveNumber:
    """Finite numbers > 0."""

    def parse(self, text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise ValueError(f"expected a number, got {text!r}") from None
        if not 0.0 < value < math.inf:
            raise ValueError(f"expected a finite number > 0, got {text}")
        return value

    def check(self, name: str, value) -> None:
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            raise InvalidInputError(f"{name} must be a number, got {value!r}")
        if not 0.0 < float(value) < math.inf:
            raise InvalidInputError(f"{name} must be a finite number > 0, got {value}")


@dataclass(frozen=True)
class Choice:
    """One of a few words (argparse lists them in its own message on the command line)."""

    choices: tuple[str, ...]

    def parse(self, text: str) -> str:
        return text

    def check(self, name: str, value) -> None:
        if value not in self.choices:
            raise InvalidInputError(f"{name} must be one of {', '.join(self.choices)}, got {value!r}")


@dataclass(frozen=True)
class Text:
    """Any word (its meaning is checked where it is used: a colouring names a field of the file)."""

    def parse(self, text: str) -> str:
        return text

    def check(self, name: str, value) -> None:
        if not isinstance(value, str):
            raise InvalidInputError(f"{name} must be a string, got {value!r}")


@dataclass(frozen=True)
class Switch:
    """On or off: a flag without a value on the command line, True or False in Python."""

    def check(self, name: str, value) -> None:
        if not isinstance(value, bool):
            raise InvalidInputError(f"{name} must be True or False, got {value!r}")


@dataclass(frozen=True)
class Option:
    """One meshing option.

    name:     its Python keyword; the flag is ``--`` + name with ``-`` for ``_``.
    value:    how it is parsed from the command line and checked in Python (a Switch takes none).
    help:     the flag's help text.
    default:  its value for centreline inputs when not given (TubeOptions' default); a scene
              file states its own resolution, which an option not given leaves as it is.
    inputs:   the kinds of input it concerns: given for another kind on the command line it is
              refused (``elsewhere`` says what to do instead); ``cgamesh batch`` passes each
              input only the options of its kind.
    keyword:  the kinds whose ``cgamesh.load`` takes it (what the pipeline receives); empty for
              an option only the writers or the command line read.
    writes:   the part of the writers' WriteOptions it fills ("gltf"), or None.
    group:    its --help section; metavar: the flag's value in --help.
    elsewhere: what to give instead, in the refusal for an input of another kind.
    stricter: a stricter check of the value for one kind of input (``around``: a tube needs 3
              vertices around, where a ribbon is 2 across); ``value_for(kind)``.
    """

    name: str
    value: WholeNumber | PositiveNumber | Choice | Text | Switch
    help: str
    default: object = None
    inputs: frozenset[InputKind] = BOTH
    keyword: frozenset[InputKind] | None = None  # None: the kinds of ``inputs``
    writes: str | None = None
    group: Group = Group.MESHING
    metavar: str | None = None
    elsewhere: str | None = None
    stricter: tuple[tuple[InputKind, WholeNumber | PositiveNumber], ...] = ()

    @property
    def flag(self) -> str:
        return "--" + self.name.replace("_", "-")

    @property
    def keyword_for(self) -> frozenset[InputKind]:
        return self.inputs if self.keyword is None else self.keyword

    def value_for(self, kind: InputKind | None):
        """The check a value of this option passes for an input of ``kind`` (None: any kind)."""
        return dict(self.stricter).get(kind, self.value)

    @property
    def is_switch(self) -> bool:
        return isinstance(self.value, Switch)

    def given(self, value) -> bool:
        """Whether ``value`` asks for something: a switch that is on, any other value but None."""
        return value is True if self.is_switch else value is not None


@dataclass(frozen=True)
class Exclusive:
    """Options that exclude each other: ``option`` with any of ``others``, for inputs of ``inputs``.

    ``message`` names them by ``{name}`` fields, spelled as flags on the command line and in
    batch, as keywords in ``cgamesh.load``."""

    option: str
    others: tuple[str, ...]
    message: str
    inputs: frozenset[InputKind] = BOTH

    def refuse(self, values: Mapping, spell) -> None:
        if _given(self.option, values.get(self.option)) and any(_given(o, values.get(o)) for o in self.others):
            names = {name: spell(name) for name in (self.option, *self.others)}
            raise InvalidInputError(self.message.format(**names))


OPTIONS: tuple[Option, ...] = (
    Option("around", WholeNumber(2), "vertices around every circle, or across every ribbon (overrides the file)",
           default=8, stricter=((CENTERLINES, WholeNumber(3)),)),
    Option("along", WholeNumber(2), "rings along every surface (overrides the file)", inputs=frozenset({SCENE}),
           elsewhere="for centreline inputs give --subdivide K (rings between consecutive nodes)"),
    Option("tolerance", PositiveNumber(), "largest distance of every mesh from its true surface, in file units "
                                          "(instead of a resolution; overrides the file)"),
    Option("tangents", Switch(), "glTF: write a TANGENT attribute (so normal maps work)", default=False,
           keyword=frozenset({SCENE}), writes="gltf"),
    Option("quantize", Switch(), "glTF: store positions, normals and UVs in 16 / 8 bits (KHR_mesh_quantization)",
           default=False, keyword=frozenset(), writes="gltf"),
    Option("strict", Switch(), "with --report: exit 1 when a quality threshold is broken; centreline inputs: "
                               "a segment that cannot be meshed stops the run (exit 2, nothing written)",
           default=False, keyword=frozenset({CENTERLINES})),
    Option("radius", PositiveNumber(), "a constant tube radius (required where the file has none)",
           inputs=frozenset({CENTERLINES}), group=Group.CENTERLINES),
    Option("min_radius", PositiveNumber(), "raise smaller radii (and radius 0) to this",
           inputs=frozenset({CENTERLINES}), group=Group.CENTERLINES),
    Option("units", Choice(tuple(METERS_PER_UNIT)), "the file's length unit (default: the format's, "
                                                    "SWC um, trk/tck/trx mm, npz m)",
           inputs=frozenset({CENTERLINES}), group=Group.CENTERLINES),
    Option("up", Choice(UP_AXES), "which axis of the file points up (default z)", default="z",
           inputs=frozenset({CENTERLINES}), group=Group.CENTERLINES),
    Option("subdivide", WholeNumber(0), "rings between consecutive nodes (default 3)", default=3,
           inputs=frozenset({CENTERLINES}), group=Group.CENTERLINES),
    Option("color_by", Text(), "vertex colours: by radius, |tangent| RGB, segment, or a per-point field of the file",
           default="none", inputs=frozenset({CENTERLINES}), group=Group.CENTERLINES,
           metavar="|".join(COLOR_MODES) + "|SCALAR"),
    Option("split", Switch(), "one mesh per segment / streamline instead of one mesh", default=False,
           inputs=frozenset({CENTERLINES}), group=Group.CENTERLINES),
    Option("watertight", Switch(), "one closed 2-manifold surface (capped tubes, junctions and soma united)",
           default=False, inputs=frozenset({CENTERLINES}), group=Group.CENTERLINES),
    Option("caps", Switch(), "close every tube's ends with flat discs (implied by --watertight)", default=False,
           inputs=frozenset({CENTERLINES}), group=Group.CENTERLINES),
    Option("keep_going", Switch(), "skip segments that cannot be meshed, exit 3 (the default; --strict stops instead)",
           default=False, inputs=frozenset({CENTERLINES}), keyword=frozenset(), group=Group.CENTERLINES),
)

EXCLUSIVE: tuple[Exclusive, ...] = (
    Exclusive("tolerance", ("around", "along"), "{tolerance} cannot be combined with {around} or {along}",
              frozenset({SCENE})),
    Exclusive("tolerance", ("around", "subdivide"), "{tolerance} cannot be combined with {around} or {subdivide}",
              frozenset({CENTERLINES})),
    Exclusive("keep_going", ("strict",), "{keep_going} and {strict} exclude each other", frozenset({CENTERLINES})),
    Exclusive("watertight", ("split",), "{watertight} makes one surface; it cannot be combined with {split}",
              frozenset({CENTERLINES})),
)

BY_NAME: dict[str, Option] = {option.name: option for option in OPTIONS}


def flag(name: str) -> str:
    """How the command line spells option ``name``: ``--min-radius``."""
    return BY_NAME[name].flag


def keywords(kind: InputKind) -> tuple[str, ...]:
    """The options ``cgamesh.load`` takes for an input of ``kind``, in table order."""
    return tuple(option.name for option in OPTIONS if kind in option.keyword_for)


def given(values: Mapping) -> dict:
    """The options of ``values`` that were given (see the module docstring), unknown names kept."""
    return {name: value for name, value in values.items() if _given(name, value)}


def for_input(values: Mapping, kind: InputKind) -> dict:
    """The given options of ``values`` that ``cgamesh.load`` takes for an input of ``kind``."""
    wanted = keywords(kind)
    return {name: value for name, value in given(values).items() if name in wanted}


def write_keywords() -> tuple[str, ...]:
    """The options that fill a part of the writers' WriteOptions (``Meshes.export``'s keywords)."""
    return tuple(option.name for option in OPTIONS if option.writes is not None)


def check_keywords(values: Mapping, allowed: tuple[str, ...], kind: InputKind | None = None) -> None:
    """Refuse a keyword not in ``allowed`` (one line listing them), a value of the wrong type or
    range, and a combination EXCLUSIVE refuses for ``kind`` (named as keywords)."""
    unknown = sorted(set(values) - set(allowed))
    if unknown:
        raise InvalidInputError(f"unknown option {unknown[0]!r}; expected one of {', '.join(allowed)}")
    for name, value in values.items():
        if value is not None:
            BY_NAME[name].value_for(kind).check(name, value)
    if kind is not None:
        refuse_exclusive(values, {kind}, spell=str)


def refuse_elsewhere(values: Mapping, kind: InputKind, source: str) -> None:
    """The command line's refusal of an option given for an input (``source``, of ``kind``) it
    does not concern, saying which inputs it is for and, where the table says, what to give instead."""
    from cgamesh.inputs import formats

    for option in OPTIONS:
        if kind not in option.inputs and option.given(values.get(option.name)):
            if SCENE in option.inputs:
                where = "scene files"
            else:
                where = f"centreline inputs ({', '.join(formats.suffixes(CENTERLINES))})"
            if option.elsewhere is not None:
                raise InvalidInputError(f"{option.flag} applies to {where}; {option.elsewhere}")
            this = "the scene file" if kind is SCENE else "the centreline input"
            raise InvalidInputError(f"{option.flag} applies to {where}, not to {this} {source}")


def refuse_exclusive(values: Mapping, kinds, spell=flag) -> None:
    """InvalidInputError for the first combination of EXCLUSIVE (for any of ``kinds``) in ``values``."""
    for rule in EXCLUSIVE:
        if rule.inputs & set(kinds):
            rule.refuse(values, spell)


def check_batch(values: Mapping) -> None:
    """Refuse unknown or contradictory batch options once, before any input is meshed."""
    unknown = sorted(set(values) - set(BY_NAME))
    if unknown:
        raise InvalidInputError(f"unknown meshing option{'s' if len(unknown) > 1 else ''} {', '.join(unknown)}; "
                                f"expected some of {', '.join(sorted(BY_NAME))}")
    for name, value in values.items():
        if value is not None:
            BY_NAME[name].value.check(name, value)
    refuse_exclusive(values, BOTH)


def for_writer(values: Mapping, part: str) -> dict:
    """The given options of ``values`` that fill the writers' part ``part`` ("gltf")."""
    return {name: value for name, value in given(values).items() if name in BY_NAME and BY_NAME[name].writes == part}


def _given(name: str, value) -> bool:
    option = BY_NAME.get(name)
    return value is not None if option is None else option.given(value)

