"""The table of input formats: which file is read by which reader, as which kind of input.

One ``InputFormat`` owns everything about a format: the suffixes that name it (and, for files
whose suffix names no format, an optional probe of the file's first bytes), its reader, the
kind of input it is (a scene of CGA surfaces, or centrelines to put tubes around) and, for
centrelines, the length unit its coordinates are in unless ``--units`` says otherwise. The
options a format takes are those of its kind in the table of meshing options
(``cgamesh.options.keywords(kind)``), so a format cannot take an option its pipeline ignores.

Everything that needs to know the formats asks this table: ``cgamesh.load``, the command
line's choice between the scene and the centreline path, ``cgamesh batch``'s search of folders,
and the messages that list the known suffixes.

The built-in formats are listed in ``BUILT_IN`` below. An extension registers its own with
``register(...)``; a separate process (the command line, ``cgamesh batch``'s workers) imports
the modules named in the environment variable ``CGAMESH_PLUGINS`` (comma-separated module
names) the first time it consults the table, so a module that calls ``register`` there adds
its format everywhere without a change to the package::

    # polylines_format.py, on the Python path
    from cgamesh.inputs.formats import register
    register("text polylines", [".polyl"], "polylines_format:read", units="m")

    $ CGAMESH_PLUGINS=polylines_format cgamesh lines.polyl -o lines.glb --radius 0.1

(An environment variable rather than package-metadata entry points: it works for a module that
is not an installed distribution, Dask workers inherit it, and reading it costs nothing, where
entry points import importlib.metadata and scan every installed distribution on each start.)

Readers are imported only when a file of their format is read, so nibabel and trx-python are
loaded only for tractograms. A centreline reader is called as ``reader(path, units=UNIT)`` and
returns a ``cgamesh.inputs.centerlines.Centerlines``; a scene reader as ``reader(path, **how)``
(``rendering=False``: the meshing does not read the rendering keys) and returns a Scene.
"""

from __future__ import annotations

import enum
import importlib
import os
from collections.abc import Callable, Iterable
from dataclasses import dataclass

from cgamesh.errors import InvalidInputError
from cgamesh.inputs.units import METERS_PER_UNIT

PLUGINS_VARIABLE = "CGAMESH_PLUGINS"
# How much of a file a probe sees: enough for every magic number and header line we know of.
PROBE_BYTES = 512


class InputKind(enum.Enum):
    """What an input becomes: a scene's surfaces (CGA circles, point pairs) or tubes along
    centrelines. The kind decides the pipeline and the options an input takes."""

    SCENE = "scene"
    CENTERLINES = "centerlines"


@dataclass(frozen=True)
class InputFormat:
    """One input format.

    name:     how messages and the README name it ("SWC neuron skeleton").
    suffixes: the file name endings that name it, lower case with their dot (".swc").
    kind:     InputKind.SCENE or InputKind.CENTERLINES.
    reader:   "module:function", imported on the first read, or the function itself.
    units:    centrelines: the length unit of the format's coordinates (a key of
              METERS_PER_UNIT), used unless ``--units`` is given; None for scenes, whose file
              states its own unit.
    probe:    optional ``probe(head: bytes) -> bool``: whether a file whose suffix names no
              format is of this one, from its first PROBE_BYTES bytes.
    """

    name: str
    suffixes: tuple[str, ...]
    kind: InputKind
    reader: str | Callable
    units: str | None = None
    probe: Callable[[bytes], bool] | None = None

    def read(self, path: str | os.PathLike[str], **arguments):
        """The file at ``path`` read by this format's reader (imported now, if named)."""
        reader = self.reader
        if isinstance(reader, str):
            module, _, function = reader.partition(":")
            reader = getattr(importlib.import_module(module), function)
        return reader(path, **arguments)


# The formats cgamesh reads itself, in the order messages list them.
BUILT_IN: tuple[InputFormat, ...] = (
    InputFormat("scene file", (".yaml", ".yml"), InputKind.SCENE, "cgamesh.inputs.scene:load_scene"),
    InputFormat("SWC neuron skeleton", (".swc",), InputKind.CENTERLINES, "cgamesh.inputs.swc:read_swc", "um"),
    InputFormat("TrackVis tractogram", (".trk",), InputKind.CENTERLINES,
                "cgamesh.inputs.streamlines:read_streamlines", "mm"),
    InputFormat("MRtrix tractogram", (".tck",), InputKind.CENTERLINES,
                "cgamesh.inputs.streamlines:read_streamlines", "mm"),
    InputFormat("TRX tractogram", (".trx",), InputKind.CENTERLINES,
                "cgamesh.inputs.streamlines:read_streamlines", "mm"),
    InputFormat("NumPy arrays", (".npz",), InputKind.CENTERLINES, "cgamesh.inputs.arrays:read_npz", "m"),
)

_formats: list[InputFormat] = list(BUILT_IN)
_plugins_loaded: set[str] = set()


def register(name: str, suffixes: Iterable[str], reader: str | Callable, *, units: str = "m",
             kind: InputKind = InputKind.CENTERLINES, probe: Callable[[bytes], bool] | None = None) -> InputFormat:
    """Add an input format to the table; returns it. ``suffixes`` e.g. ``[".polyl"]``; the other
    arguments as the fields of InputFormat (``units`` is ignored for scenes).

    A suffix another format already owns is refused: two readers for one suffix would make
    which one reads a file depend on the order of registration.
    """
    wanted = tuple(suffixes)
    if not wanted or any(not isinstance(s, str) or not s.startswith(".") or s != s.lower() or len(s) < 2
                         for s in wanted):
        raise InvalidInputError(f"input format {name!r}: expected suffixes such as '.swc' (lower case, with "
                                f"the dot), got {list(wanted)}")
    if not isinstance(kind, InputKind):
        raise InvalidInputError(f"input format {name!r}: expected kind InputKind.SCENE or InputKind.CENTERLINES, "
                                f"got {kind!r}")
    if kind is InputKind.CENTERLINES and units not in METERS_PER_UNIT:
        raise InvalidInputError(f"input format {name!r}: units must be one of {', '.join(METERS_PER_UNIT)}, "
                                f"got {units!r}")
    if not (callable(reader) or (isinstance(reader, str) and ":" in reader)):
        raise InvalidInputError(f"input format {name!r}: expected a reader function or 'module:function', "
                                f"got {reader!r}")
    for suffix in wanted:
        owner = _by_suffix(suffix)
        if owner is not None:
            raise InvalidInputError(f"input format {name!r}: the suffix {suffix} is already the {owner.name}'s")
    added = InputFormat(name, wanted, kind, reader, units if kind is InputKind.CENTERLINES else None, probe)
    _formats.append(added)
    return added


def unregister(added: InputFormat) -> None:
    """Take a format added by ``register`` out of the table again (tests; a built-in stays)."""
    if added in BUILT_IN:
        raise InvalidInputError(f"the built-in {added.name} format cannot be removed")
    _formats.remove(added)


def formats() -> tuple[InputFormat, ...]:
    """Every known format: the built-in ones, then the registered ones in their order."""
    load_plugins()
    return tuple(_formats)


def suffixes(kind: InputKind | None = None) -> tuple[str, ...]:
    """Every suffix of the formats of ``kind`` (of every format when None), in table order."""
    return tuple(s for f in formats() if kind is None or f.kind is kind for s in f.suffixes)


def find(path: str | os.PathLike[str]) -> InputFormat | None:
    """The format of the file at ``path``: by its suffix (case-insensitive), else by the probes
    of the formats that have one, shown the file's first bytes; None when neither tells."""
    load_plugins()
    suffix = os.path.splitext(os.fspath(path))[1].lower()
    owner = _by_suffix(suffix)
    if owner is not None:
        return owner
    probing = [f for f in _formats if f.probe is not None]
    if probing:
        try:
            with open(path, "rb") as stream:
                head = stream.read(PROBE_BYTES)
        except OSError:  # the reader's own message says why, once a format is chosen
            return None
        for candidate in probing:
            if candidate.probe(head):
                return candidate
    return None


def format_of(path: str | os.PathLike[str]) -> InputFormat:
    """As ``find``, but a file of no known format is an InvalidInputError naming the suffixes."""
    found = find(path)
    if found is None:
        suffix = os.path.splitext(os.fspath(path))[1].lower()
        raise InvalidInputError(
            f"{os.fspath(path)}: unknown input format {suffix or '(no extension)'!r}; expected a scene file "
            f"({', '.join(suffixes(InputKind.SCENE))}) or one of {', '.join(suffixes(InputKind.CENTERLINES))}")
    return found


def read_centerlines(path: str | os.PathLike[str], units: str | None = None):
    """The Centerlines of any centreline file; ``units`` overrides the format's own unit."""
    found = format_of(path)
    if found.kind is not InputKind.CENTERLINES:
        raise InvalidInputError(f"{os.fspath(path)}: a {found.name} holds no centrelines; expected one of "
                                f"{', '.join(suffixes(InputKind.CENTERLINES))}")
    if units is not None and units not in METERS_PER_UNIT:
        raise InvalidInputError(f"units must be one of {', '.join(METERS_PER_UNIT)}, got {units!r}")
    return found.read(path, units=units or found.units)


def load_plugins() -> None:
    """Import each module named in CGAMESH_PLUGINS not imported yet (each registers its formats)."""
    names = [n.strip() for n in os.environ.get(PLUGINS_VARIABLE, "").split(",") if n.strip()]
    for name in names:
        if name in _plugins_loaded:
            continue
        _plugins_loaded.add(name)  # first: a plugin that consults the table while importing
        try:
            importlib.import_module(name)
        except ImportError as error:
            _plugins_loaded.discard(name)
            raise InvalidInputError(f"{PLUGINS_VARIABLE}: cannot import the plugin module {name!r}: {error}") from None


def _by_suffix(suffix: str) -> InputFormat | None:
    for candidate in _formats:
        if suffix in candidate.suffixes:
            return candidate
    return None
