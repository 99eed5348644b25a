"""Fuzzing the command line with mutated example scenes: the error contract holds for each.

Every example scene is mutated, seeded (values replaced by numbers at float64's ends, NaN,
infinities, strings, booleans, lists and mappings; keys deleted or duplicated; lines swapped,
deleted or duplicated; the text truncated or junk inserted), and meshed by the CLI in-process
with numpy's warnings as errors. Each run either succeeds (a GLB is written) or exits 2 with
exactly one stderr line ``cgamesh: error: FILE:LINE: ...``; no traceback, no warning, and a
file already at the output path is left untouched by a failed run. CI runs a small count;
CGAMESH_FUZZ_COUNT asks for more (CGAMESH_FUZZ_SEED for another sequence).
"""

from __future__ import annotations

import contextlib
import io
import os
import random
import re
import warnings
from pathlib import Path

import pytest
import yaml

from cgamesh_cli.main import main

EXAMPLES = sorted((Path(__file__).parent.parent / "examples").glob("*.yaml"))
COUNT = int(os.environ.get("CGAMESH_FUZZ_COUNT", "80"))
SEED = int(os.environ.get("CGAMESH_FUZZ_SEED", "20261201"))
PREVIOUS = b"an output from an earlier run"

STRANGE_VALUES = [0, -1, 1, 2, 3, 0.0, -0.0, 1e308, -1e308, 1e-308, 5e-324, -5e-324, 1e-300, 1e300, 1e-9,
                  1e9, 10**30, float("nan"), float("inf"), float("-inf"), "abc", "", True, False, None,
                  [], [0], [0, 0, 0], [1, 2, 3, 4], [[0, 0, 0]] * 3, {}, {"a": 1}, "1e-4", 2**64]
JUNK = ["\t", "\x00", "\ufeff", "{", "}", "[", "]", ":", "- ", "&a ", "*a", "!!python/object:os.system ",
        "%YAML 1.2\n", "---\n", "...\n", "#", "'", '"', "\\", "\n  ", "é", "\u2028", "? ", "|\n", ">\n"]


def _paths(tree, prefix=()):
    """Every (path, value) in a loaded YAML tree, paths as tuples of keys and indices."""
    yield prefix, tree
    if isinstance(tree, dict):
        for key, value in tree.items():
            yield from _paths(value, prefix + (key,))
    elif isinstance(tree, list):
        for i, value in enumerate(tree):
            yield from _paths(value, prefix + (i,))


def _parent(tree, path):
    for key in path[:-1]:
        tree = tree[key]
    return tree


def mutate(text: str, rng: random.Random) -> str:
    """One seeded mutation of a scene file's text."""
    kind = rng.choice(["value", "value", "value", "delete_key", "duplicate_key", "lines", "truncate", "junk"])
    tree = None
    if kind in ("value", "delete_key", "duplicate_key"):
        try:
            tree = yaml.safe_load(text)
        except yaml.YAMLError:  # an earlier mutation broke the YAML: mutate the text instead
            kind = "junk"
    paths = [p for p, _ in _paths(tree) if p] if isinstance(tree, (dict, list)) else []
    if not paths and kind in ("value", "delete_key", "duplicate_key"):
        kind = "truncate"
    if kind in ("value", "delete_key", "duplicate_key"):
        path = rng.choice(paths)
        parent = _parent(tree, path)
        if kind == "value":
            parent[path[-1]] = rng.choice(STRANGE_VALUES)
        elif kind == "delete_key":
            del parent[path[-1]]
        out = yaml.safe_dump(tree, default_flow_style=None, sort_keys=False)
        if kind == "duplicate_key":
            lines = [line for line in out.splitlines() if re.match(r"^\s*(- )?[a-z_]+:", line)]
            if lines:
                line = rng.choice(lines)
                out = out.replace(line, line + "\n" + re.sub(r"^(\s*)- ", r"\1  ", line), 1)
        return out
    lines = text.splitlines(keepends=True)
    if kind == "lines" and lines:
        i, j = rng.randrange(len(lines)), rng.randrange(len(lines))
        action = rng.choice(["swap", "delete", "duplicate"])
        if action == "swap":
            lines[i], lines[j] = lines[j], lines[i]
        elif action == "delete":
            del lines[i]
        else:
            lines.insert(j, lines[i])
        return "".join(lines)
    if kind == "truncate":
        return text[: rng.randrange(len(text) + 1)]
    at = rng.randrange(len(text) + 1)
    return text[:at] + rng.choice(JUNK) + text[at:]


def run_cli(argv):
    out, err = io.StringIO(), io.StringIO()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            status = main([str(a) for a in argv])
    return status, err.getvalue()


def cases():
    rng = random.Random(SEED)
    texts = [(path.name, path.read_text(encoding="utf-8")) for path in EXAMPLES]
    for number in range(COUNT):
        name, text = texts[number % len(texts)]
        mutated = text
        for _ in range(rng.choice([1, 1, 1, 2, 3])):
            mutated = mutate(mutated, rng)
        yield pytest.param(mutated, id=f"{number}-{name}")


@pytest.mark.parametrize("text", list(cases()))
def test_mutated_scene_succeeds_or_fails_in_one_line(tmp_path, text):
    scene = tmp_path / "mutated.yaml"
    scene.write_bytes(text.encode("utf-8", "surrogatepass"))
    output = tmp_path / "out.glb"
    output.write_bytes(PREVIOUS)
    status, err = run_cli([scene, "-o", output, "--around", "6", "--along", "6", "-q"])
    if status == 0:
        assert err == ""
        assert output.read_bytes()[:4] == b"glTF"
    else:
        assert status == 2, err
        lines = err.splitlines()
        assert len(lines) == 1, err
        assert re.match(rf"cgamesh: error: {re.escape(str(scene))}:\d+: ", lines[0]), lines[0]
        assert output.read_bytes() == PREVIOUS
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mutated.yaml", "out.glb"]
