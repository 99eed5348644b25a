"""Which files a batch meshes, and where each one's outputs go.

Inputs are files, folders (searched recursively for the known input extensions), glob patterns
(``**`` allowed) or a listing file of one path a line. Each input's outputs keep its path
relative to the common folder of all inputs, under the output folder, with the extension of
each format: ``data/a/n1.yaml`` and ``data/b/n2.yaml`` become ``OUT/a/n1.glb`` and
``OUT/b/n2.glb``.
"""

from __future__ import annotations

import glob
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

from cgamesh.errors import InvalidInputError

GLOB_CHARACTERS = frozenset("*?[")


@dataclass(frozen=True)
class Input:
    """One input of a batch: its file, its name relative to the inputs' common folder (the key of
    the manifest), and its outputs, or ``missing`` when it was named but does not exist."""

    path: Path
    name: str
    outputs: tuple[Path, ...]
    missing: bool = False


def discover(inputs: Iterable[str | os.PathLike], listing: str | os.PathLike | None = None,
             extensions: Sequence[str] = (".yaml", ".yml")) -> list[Path]:
    """The input files named by ``inputs`` and ``listing``, each once, in the order given
    (a folder's and a glob's files sorted). Named paths that do not exist are kept, so that
    they are reported as failed inputs instead of stopping the others."""
    named = [str(item) for item in inputs]
    if listing is not None:
        named += read_listing(listing)
    found: list[Path] = []
    for item in named:
        path = Path(item)
        if path.is_dir():
            found += sorted(p for p in path.rglob("*")
                            if p.suffix.lower() in extensions and p.is_file() and not _hidden(p.relative_to(path)))
        elif not path.exists() and GLOB_CHARACTERS & set(item):
            found += sorted(Path(p) for p in glob.glob(item, recursive=True) if Path(p).is_file())
        else:
            found.append(path)
    unique: dict[Path, Path] = {}
    for path in found:
        unique.setdefault(path.resolve(), path)
    if not unique:
        raise InvalidInputError(f"no input files found in {', '.join(named) or 'the command line'} "
                                f"(folders are searched for {', '.join(extensions)})")
    return list(unique.values())


def read_listing(listing: str | os.PathLike) -> list[str]:
    """The paths of a listing file, one a line; blank lines and lines starting with # are
    skipped, and relative paths are relative to the listing file's folder."""
    try:
        lines = Path(listing).read_text(encoding="utf-8-sig").splitlines()
    except OSError as error:
        raise InvalidInputError(f"{listing}: cannot read the list of inputs: {error.strerror or error}") from None
    except UnicodeDecodeError:
        raise InvalidInputError(f"{listing}: the list of inputs must be UTF-8 text, one path a line") from None
    folder = Path(listing).parent
    return [str(folder / line.strip()) for line in lines if line.strip() and not line.lstrip().startswith("#")]


def plan_outputs(paths: Sequence[Path], outdir: str | os.PathLike, formats: Sequence[str]) -> list[Input]:
    """Each input with its name and output paths (one per format, e.g. ``glb``). Two inputs that
    would write the same output (``a.yaml`` and ``a.yml``) are an error naming both."""
    resolved = [p.resolve() for p in paths]
    existing = [r for r, p in zip(resolved, paths) if p.exists()]
    root = Path(os.path.commonpath([str(r.parent) for r in existing])) if existing else Path.cwd()
    outdir = Path(outdir)
    planned: list[Input] = []
    owners: dict[Path, Path] = {}
    for path, full in zip(paths, resolved):
        relative = full.relative_to(root) if full.is_relative_to(root) else Path(full.name)
        outputs = tuple(outdir / relative.with_suffix("." + fmt.lstrip(".").lower()) for fmt in formats)
        for output in outputs:
            if output in owners:
                raise InvalidInputError(f"{owners[output]} and {path} would both be written to {output}; "
                                        "rename one of them or mesh them in separate batches")
            owners[output] = path
        planned.append(Input(path, relative.as_posix(), outputs, missing=not path.exists()))
    return planned


def _hidden(relative: Path) -> bool:
    """A file or folder whose name starts with a dot (temporary files of atomic writes among them)."""
    return any(part.startswith(".") for part in relative.parts)
