"""The scene reader's fast path against the careful reader, the reference.

For any text, ``parse_scene`` with the fast path must give what the careful reader alone
gives: the same Scene (every spec, every Location), or the same exception with the same
one-line message (same file:line). The fast path must also actually be taken on the shape
scene files are written in, or it is no fast path.
"""

from __future__ import annotations

import random
from pathlib import Path

import pytest
from hypothesis import given, settings, strategies as st

from cgamesh.errors import InvalidInputError
from cgamesh.inputs.scene import parse_scene
from cgamesh.inputs.scene_fast import read_fast
from test_fuzz_scenes import mutate

EXAMPLES = sorted((Path(__file__).parent.parent / "examples").glob("*.yaml"))


def outcome(text: str, fast: bool, rendering: bool = True):
    """The Scene, or (exception type, message) of what parse_scene raises."""
    try:
        return parse_scene(text, "scene.yaml", rendering, fast=fast)
    except InvalidInputError as exc:
        return type(exc), str(exc)


def assert_same(text: str, rendering: bool = True):
    fast, careful = outcome(text, True, rendering), outcome(text, False, rendering)
    assert fast == careful, text


@pytest.mark.parametrize("rendering", [True, False])
@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.stem)
def test_every_example_reads_the_same_and_meshing_takes_the_fast_path(path, rendering):
    text = path.read_text(encoding="utf-8")
    careful = parse_scene(text, str(path), rendering, fast=False)
    fast = read_fast(text, str(path), rendering)
    if rendering and not path.stem.startswith("traced_"):
        assert fast == careful
    if not rendering:  # what meshing reads: every example is in the fast path's subset
        assert fast == careful
    assert parse_scene(text, str(path), rendering) == careful


def _fuzz_cases(count: int = 300, seed: int = 13):
    """Mutated examples (as the CLI fuzz test makes them: flow lists of numbers), each also in
    PyYAML's block layout (a list item per line), where it still loads."""
    import yaml

    rng = random.Random(seed)
    texts = [path.read_text(encoding="utf-8") for path in EXAMPLES]
    for number in range(count):
        text = texts[number % len(texts)]
        for _ in range(rng.choice([1, 1, 2, 3])):
            text = mutate(text, rng)
        yield text
        try:
            yield yaml.safe_dump(yaml.safe_load(text), sort_keys=False, default_flow_style=False)
        except (yaml.YAMLError, RecursionError):
            pass


@pytest.mark.parametrize("text", [pytest.param(text, id=str(i)) for i, text in enumerate(_fuzz_cases())])
def test_mutated_examples_give_the_same_scene_or_the_same_located_error(text):
    assert_same(text, rendering=False)
    assert_same(text, rendering=True)


# Texts where YAML and a naive JSON reading differ, or that the subset must leave to the
# careful reader (security: aliases, anchors, tags; duplicate keys).
HEAD = "cgamesh: 1\nsurfaces:\n  - name: t\n    type: circles\n    curve: linear\n    controls:\n"
GOOD = ("      - {center: [0, 0, 0], normal: [0, 0, 1], radius: 1}\n"
        "      - {center: [0, 0, 1], normal: [0, 0, 1], radius: 1}\n")
EDGES = [
    GOOD.replace("radius: 1}\n", "radius:1}\n", 1),  # 'radius:1' is one plain scalar in YAML
    GOOD.replace("[0, 0, 0]", "[0, 0, 0], [1]", 1),
    GOOD.replace("[0, 0, 0]", "[00, 0, 0]", 1),
    GOOD.replace("[0, 0, 0]", "[0, 0, .5]", 1),
    GOOD.replace("[0, 0, 0]", "[0, 0, 1e400]", 1),
    GOOD.replace("[0, 0, 0]", "[0, 0, NaN]", 1),
    GOOD.replace("[0, 0, 0]", "[0, 0, true]", 1),
    GOOD.replace("[0, 0, 0]", "[0, 0, 0,]", 1),
    GOOD.replace("[0, 0, 0]", "[0, 0, 1" + "0" * 400 + "]", 1),
    GOOD.replace("radius: 1}", "radius: 1, radius: 2}", 1),
    GOOD.replace("radius: 1}", "radius: 0}", 1),
    GOOD.replace("radius: 1}", "radius: -0.0}", 1),
    GOOD.replace("normal: [0, 0, 1]", "normal: [0, -0.0, 0]", 1),
    GOOD.replace("normal: [0, 0, 1]", "normal: [0, 0]", 1),
    GOOD.replace("      - {center: [0, 0, 0]", "      - &a {center: [0, 0, 0]", 1) + "      - *a\n",
    GOOD.replace("radius: 1}", "radius: !!float 1}", 1),
    GOOD.replace("radius: 1}", "radius: !!python/object/apply:os.system [echo]}", 1),
    GOOD.replace("{center", "{\"center\"", 1),
    GOOD.replace("{center: [0, 0, 0],", "{center: [0, 0,\n        0],", 1),
    GOOD + "    resolution: {around: 8, along: 16}\n    resolution: {around: 8}\n",
    GOOD + "    resolution:\n      around: 8\n      around: 9\n",
    GOOD + "    resolution:\n      around: 8.0\n",
    GOOD + "    resolution:\n    around: 8\n",
    GOOD + "    caps: True\n",
    GOOD + "    caps: yes\n",
    GOOD + "    caps: ~\n",
    GOOD + "    caps:\n",
    GOOD + "    caps: true # closed ends\n",
    GOOD + "    caps: true#x\n",
    GOOD + "    name: again\n",
    GOOD + "    material: {color: [1, 0.5, 0], roughness: 1}\n",
    GOOD + "    material: {color: [1, 0.5, 2]}\n",
    GOOD + "    material:\n      color: [1, 0.5, 0]\n      metallic: 1.5\n",
    GOOD + "    tolerance: 1e-3\n",
    GOOD + "    tolerance: 1e-3\n    resolution: {around: 8}\n",
    GOOD + "  - name: t\n    type: circles\n    curve: linear\n    controls:\n" + GOOD,
    GOOD + "---\n",
    GOOD + "    uv: none\n    uv_scale: 2\n",
    GOOD.replace("      - {", "      -   {", 1),
    GOOD.replace("      - ", "    - "),
    GOOD.replace("      - {center: [0, 0, 0], normal: [0, 0, 1], radius: 1}",
                 "      - center: [0, 0, 0]\n        normal: [0, 0, 1]\n        radius: 1", 1),
    GOOD.replace("      - {center: [0, 0, 0], normal: [0, 0, 1], radius: 1}",
                 "      - center: [0, 0, 0]\n        normal: [0, 0, 1]\n         radius: 1", 1),
    GOOD.replace("      - {center: [0, 0, 0], normal: [0, 0, 1], radius: 1}",
                 "      - through: [[1, 0, 0], [0, 1, 0], [-1, 0, 0]]", 1),
    GOOD.replace("      - {center: [0, 0, 0], normal: [0, 0, 1], radius: 1}",
                 "      - through: [[1, 0, 0], [2, 0, 0], [3, 0, 0]]", 1),
    GOOD.replace("      - {center: [0, 0, 0], normal: [0, 0, 1], radius: 1}",
                 "      - {}", 1),
    GOOD.replace("      - {center: [0, 0, 0], normal: [0, 0, 1], radius: 1}", "      - [0]", 1),
    GOOD.replace("      - {center: [0, 0, 0], normal: [0, 0, 1], radius: 1}", "      -", 1),
    GOOD + "    bad key: 1\n",
    "      # a comment with a control character \x01\n" + GOOD,
    "      # a comment with a Unicode line break \u2028 inside\n" + GOOD,
    "      # a comment with NEL \x85 inside\n" + GOOD,
    "      # a comment in UTF-8: é\n" + GOOD,
    "\t# a tab\n" + GOOD,
    GOOD.replace("{center: [0, 0, 0], normal: [0, 0, 1], radius: 1}",
                 "center:\n        - true\n        - 0\n        - 0\n        normal: [0, 0, 1]\n        radius: 1", 1),
    GOOD.replace("{center: [0, 0, 0], normal: [0, 0, 1], radius: 1}",
                 "center:\n        - 1\n        - null\n        - 0\n        normal: [0, 0, 1]\n        radius: 1", 1),
    GOOD.replace("{center: [0, 0, 0], normal: [0, 0, 1], radius: 1}",
                 "center:\n        - 1\n        - x\n        - 0\n        normal: [0, 0, 1]\n        radius: 1", 1),
    GOOD.replace("{center: [0, 0, 0], normal: [0, 0, 1], radius: 1}",
                 "center:\n        - 1\n        - 2\n        - 0\n        normal: [0, 0, 1]\n        radius: 1", 1),
]


PAIRS = ("      - {a: [0, 0, 0], b: [1, 0, 0]}\n"
         "      - {a: [0, 0, 1], b: [1, 0, 1]}\n")
WHOLE = [
    HEAD.replace("curve: linear", "curve: kb") + GOOD + GOOD.splitlines()[0] + "\n    closed: true\n    caps: true\n",
    HEAD.replace("curve: linear", "curve: kb") + GOOD + GOOD.splitlines()[0] + "\n    closed: true\n",
    HEAD.replace("circles", "point_pairs") + PAIRS + "    caps: true\n",
    HEAD.replace("circles", "point_pairs") + PAIRS + "    interpolation: motor\n",
    HEAD.replace("circles", "point_pairs") + PAIRS.replace("[1, 0, 1]", "[0, 0, 1]"),
    HEAD.replace("circles", "point_pairs") + PAIRS.replace("[1, 0, 1]", "[0, 0, 1.0000000000000002]"),
    HEAD + GOOD + "  - name: u\n    type: circles\n    curve: linear\n    controls:\n  - name: v\n",
    HEAD.replace("curve: linear", "curve: rational_bezier") + GOOD.replace("radius: 1}", "radius: 1, weight: 1e-13}", 1),
    HEAD.replace("curve: linear", "curve: rational_bezier") + GOOD.replace("radius: 1}", "radius: 1, weight: 1e-12}", 1),
    HEAD + GOOD.replace("radius: 1}", "radius: 1, weight: 2}", 1),
]


@pytest.mark.parametrize("tail", [pytest.param(tail, id=str(i)) for i, tail in enumerate(EDGES)])
def test_subset_edges_give_what_the_careful_reader_gives(tail):
    assert_same(HEAD + tail)
    assert_same(HEAD + tail, rendering=False)


@pytest.mark.parametrize("text", [pytest.param(text, id=str(i)) for i, text in enumerate(WHOLE)])
def test_rule_edges_give_what_the_careful_reader_gives(text):
    assert_same(text)


def test_the_fast_path_refuses_what_it_cannot_vouch_for_and_takes_the_rest():
    assert read_fast(HEAD + GOOD, "s.yaml", True) is not None
    for tail in EDGES[:18]:  # all outside the subset or invalid
        assert read_fast(HEAD + tail, "s.yaml", True) is None, tail


# --- generated scenes, written in the ways people and converters write them ------------------

coordinate = st.one_of(st.integers(-5, 5), st.floats(-1e3, 1e3, allow_nan=False),
                       st.sampled_from([0.0, -0.0, 1e30, -1e30, 1e-300, 2.5e-7]))
point = st.tuples(coordinate, coordinate, coordinate)


def _number(value) -> str:
    return repr(value) if isinstance(value, float) else str(value)


def _flow(values) -> str:
    return "[" + ", ".join(_number(v) for v in values) + "]"


@st.composite
def scenes(draw):
    """(YAML text, whether it is in the fast path's subset by construction)."""
    lines = ["cgamesh: 1"]
    if draw(st.booleans()):
        lines.append(f"units: {draw(st.sampled_from(['m', 'cm', 'mm']))}")
    if draw(st.booleans()):
        lines.append("# a comment line")
    lines.append("surfaces:")
    indentless = draw(st.booleans())
    pad = "" if indentless else "  "
    for index in range(draw(st.integers(1, 4))):
        kind = draw(st.sampled_from(["circles", "point_pairs"]))
        curve = draw(st.sampled_from(["linear", "bezier", "rational_bezier", "kb", "catmull_rom"]))
        lines += [f"{pad}- name: s{index}", f"{pad}  type: {kind}", f"{pad}  curve: {curve}"]
        closed = curve in ("kb", "catmull_rom") and draw(st.booleans())
        if closed:
            lines.append(f"{pad}  closed: true")
        if curve == "kb" and draw(st.booleans()):
            lines.append(f"{pad}  tension: {_number(draw(st.floats(-1, 1)))}")
        lines.append(f"{pad}  controls:  # the controls")
        for _ in range(draw(st.integers(3 if closed else 2, 5))):
            if kind == "circles" and draw(st.integers(0, 5)) == 0:
                through = draw(st.tuples(point, point, point))
                fields = {"through": "[" + ", ".join(_flow(p) for p in through) + "]"}
            elif kind == "circles":
                fields = {"center": _flow(draw(point)), "normal": _flow(draw(point)),
                          "radius": _number(draw(st.one_of(st.floats(1e-3, 1e3), st.just(0))))}
            else:
                fields = {"a": _flow(draw(point)), "b": _flow(draw(point))}
            if curve == "rational_bezier" and draw(st.booleans()):
                fields["weight"] = _number(draw(st.floats(1e-3, 1e3)))
            if draw(st.booleans()):
                lines.append(f"{pad}  - {{" + ", ".join(f"{k}: {v}" for k, v in fields.items()) + "}")
            else:
                for i, (k, v) in enumerate(fields.items()):
                    lines.append(f"{pad}  {'- ' if i == 0 else '  '}{k}: {v}")
        choice = draw(st.integers(0, 3))
        if choice == 1:
            lines.append(f"{pad}  resolution: {{around: {draw(st.integers(3, 9))}, along: {draw(st.integers(2, 9))}}}")
        elif choice == 2:
            lines += [f"{pad}  resolution:", f"{pad}    along: {draw(st.integers(2, 9))}"]
        elif choice == 3:
            lines.append(f"{pad}  tolerance: {_number(draw(st.floats(1e-6, 1.0)))}")
        if kind == "circles" and not closed and draw(st.booleans()):
            lines.append(f"{pad}  caps: true")
        if draw(st.booleans()):
            lines.append(f"{pad}  material: {{color: {_flow(draw(st.tuples(*[st.floats(0, 1)] * 3)))}}}")
    return "\n".join(lines) + "\n"


@settings(max_examples=150)
@given(scenes())
def test_generated_scenes_read_the_same_by_both_readers(text):
    careful = outcome(text, False, rendering=False)
    assert outcome(text, True, rendering=False) == careful
    if not isinstance(careful, tuple):  # valid: the fast path itself must have read it
        assert read_fast(text, "scene.yaml", False) == careful


# --- the same scenes in each layout that writers use: PyYAML's block layout (a number per
# line, '- - x' for a list in a list, indentless lists), its mixed layout (flow leaves) and a
# flow mapping per control; each read by the fast path itself when valid ---------------------

value = st.one_of(st.floats(-1e3, 1e3, allow_nan=False), st.integers(-5, 5),
                  st.sampled_from([0.0, -0.0, 1e-300, 2.5e-7, 1e9]))
# A wrong length, or a number too large for a length, now and then.
vector = st.integers(0, 19).flatmap(
    lambda odd: st.lists(value, min_size=3, max_size=3) if odd else
    st.one_of(st.lists(value, min_size=2, max_size=4), st.just([0.0, 1e30, 0.0])))


@st.composite
def scene_documents(draw):
    """A scene as plain data: every surface and control kind, the optional keys, and now and
    then a value the reader refuses (a zero radius or normal, a list of the wrong length)."""
    surfaces = []
    for index in range(draw(st.integers(1, 4))):
        kind = draw(st.sampled_from(["circles", "point_pairs"]))
        curve = draw(st.sampled_from(["linear", "bezier", "rational_bezier", "kb", "catmull_rom"]))
        closed = curve in ("kb", "catmull_rom") and draw(st.booleans())
        controls = []
        for _ in range(draw(st.integers(3 if closed else 2, 5))):
            if kind == "point_pairs":
                control = {"a": draw(vector), "b": draw(vector)}
            elif draw(st.integers(0, 5)) == 0:
                control = {"through": [draw(vector) for _ in range(3)]}
            else:
                control = {"center": draw(vector), "normal": draw(vector),
                           "radius": draw(st.floats(1e-3, 1e3)) if draw(st.integers(0, 19))
                           else 0}
            if curve == "rational_bezier" and draw(st.booleans()):
                control["weight"] = draw(st.floats(1e-3, 1e3))
            controls.append(control)
        surface = {"name": f"s{index}", "type": kind, "curve": curve, "controls": controls}
        if closed:
            surface["closed"] = True
        if kind == "circles" and not closed and draw(st.booleans()):
            surface["caps"] = True
        choice = draw(st.integers(0, 3))
        if choice == 1:
            surface["resolution"] = {"around": draw(st.integers(3, 9)),
                                     "along": draw(st.integers(2, 9))}
        elif choice == 2:
            surface["tolerance"] = draw(st.floats(1e-6, 1.0))
        if draw(st.booleans()):
            surface["material"] = {"color": draw(st.lists(st.floats(0, 1), min_size=3, max_size=3))}
        surfaces.append(surface)
    return {"cgamesh": 1, "units": draw(st.sampled_from(["m", "mm"])), "surfaces": surfaces}


def _one_line(value) -> str:
    import yaml

    # (a scalar alone comes with a document end marker on the next line)
    return yaml.safe_dump(value, default_flow_style=True, width=float("inf")).split("\n")[0]


def flow_controls_layout(document: dict) -> str:
    """Block mappings and lists, each control a flow mapping on its line (as the examples and
    the reader benchmark write them), other collections as one-line flow values."""
    lines = [f"cgamesh: {document['cgamesh']}", f"units: {document['units']}", "surfaces:"]
    for surface in document["surfaces"]:
        first = True
        for key, entry in surface.items():
            lead = "  - " if first else "    "
            first = False
            if key == "controls":
                lines.append(f"{lead}controls:")
                lines += [f"      - {_one_line(control)}" for control in entry]
            else:
                lines.append(f"{lead}{key}: {_one_line(entry)}")
    return "\n".join(lines) + "\n"


LAYOUTS = {
    "safe_dump block": lambda document: __import__("yaml").safe_dump(document, sort_keys=False),
    "safe_dump mixed": lambda document: __import__("yaml").safe_dump(
        document, sort_keys=False, default_flow_style=None),
    "flow controls": flow_controls_layout,
}


@pytest.mark.parametrize("layout", LAYOUTS)
@settings(max_examples=120)
@given(document=scene_documents())
def test_generated_scenes_in_every_layout_read_the_same_and_take_the_fast_path(layout, document):
    text = LAYOUTS[layout](document)
    careful = outcome(text, False, rendering=False)
    assert outcome(text, True, rendering=False) == careful, text
    if not isinstance(careful, tuple):  # valid: the fast path itself must have read it
        assert read_fast(text, "scene.yaml", False) == careful, text


def test_the_layouts_are_what_they_claim():
    """The generated texts have the shapes the fast path matches whole: a number per line and
    '- - x' (block), flow leaves under block controls (mixed), a flow mapping per control."""
    document = {"cgamesh": 1, "units": "m", "surfaces": [
        {"name": "t", "type": "circles", "curve": "linear", "controls": [
            {"through": [[1.0, 0, 0], [0, 1, 0], [-1, 0, 0]]},
            {"center": [0, 0, 1.5], "normal": [0, 0, 1], "radius": 1}]}]}
    block, mixed, flow = (LAYOUTS[name](document) for name in LAYOUTS)
    assert "    - - 1.0\n      - 0\n" in block and "  - center:\n    - 0\n" in block
    assert "  - center: [0, 0, 1.5]\n    normal: [0, 0, 1]\n" in mixed
    assert "      - {center: [0, 0, 1.5], normal: [0, 0, 1], radius: 1}\n" in flow
    for text in (block, mixed, flow):
        scene = read_fast(text, "scene.yaml", False)
        assert scene == parse_scene(text, "scene.yaml", False, fast=False)
        assert [c.location.line for c in scene.surfaces[0].controls] == [
            line for line, text_line in enumerate(text.splitlines(), 1)
            if text_line.lstrip().startswith("- ") and ("through" in text_line or "center" in text_line)]


def _both_json_readers(text: str) -> list[str]:
    """The fast path's result with orjson's JSON reader and with the standard library's, as
    repr (every float's bits; None when it steps aside)."""
    import cgamesh.inputs.scene_subset as subset

    results = []
    for prefer_orjson in (True, False):
        reader = subset.json_reader(prefer_orjson)
        previous, subset._read_json = subset._read_json, reader
        try:
            results.append(repr(read_fast(text, "scene.yaml", False)))
        finally:
            subset._read_json = previous
    return results


def test_orjson_is_the_fast_paths_json_reader():
    import orjson

    import cgamesh.inputs.scene_subset as subset

    assert subset.json_reader() is orjson.loads and subset._read_json is orjson.loads


@pytest.mark.parametrize("case", ["examples", "mutated", "layouts"])
def test_orjson_and_json_read_every_text_alike(case):
    """The same scene to the last bit of every float, or both step aside: on the examples in
    three layouts, the mutated examples, and generated scenes in each layout. (The plain
    data may differ where no scene can: orjson reads an integer past 64 bits as a float.)"""
    import yaml

    if case == "examples":
        texts = []
        for path in EXAMPLES:
            text = path.read_text(encoding="utf-8")
            tree = yaml.safe_load(text)
            texts += [text] + [yaml.safe_dump(tree, sort_keys=False, default_flow_style=flow)
                               for flow in (False, None)]
    elif case == "mutated":
        texts = list(_fuzz_cases(count=150, seed=29))
    else:
        texts = [layout(scene_document) for scene_document in _documents(20)
                 for layout in LAYOUTS.values()]
    for text in texts:
        with_orjson, with_json = _both_json_readers(text)
        assert with_orjson == with_json, text
    assert sum(_both_json_readers(text)[0] != "None" for text in texts) > len(texts) // 5  # read


def _documents(count: int) -> list[dict]:
    """``count`` scene documents drawn from ``scene_documents`` (hypothesis' example())."""
    import warnings

    from hypothesis.errors import NonInteractiveExampleWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NonInteractiveExampleWarning)
        return [scene_documents().example() for _ in range(count)]


def test_the_reader_benchmark_runs_at_a_small_size_and_both_readers_agree():
    import subprocess
    import sys
    script = Path(__file__).parent.parent / "benchmarks" / "bench_scene_reader.py"
    result = subprocess.run([sys.executable, str(script), "--surfaces", "20", "--repeats", "1"],
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    assert result.stdout.count("  fast path ") == 3 and "DIFFER" not in result.stderr
    assert result.stdout.count("  target >= 20 MB/s CPU, whole read: ") == 3


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.stem)
def test_examples_as_pyyaml_writes_them_read_the_same(path):
    """PyYAML's block layout (a number per line, indentless lists) and its flow-leaf layout."""
    import yaml

    document = parse_scene(path.read_text(encoding="utf-8"), str(path), fast=False)
    assert document  # the example itself is valid
    tree = yaml.safe_load(path.read_text(encoding="utf-8"))
    for flow in (False, None):
        text = yaml.safe_dump(tree, sort_keys=False, default_flow_style=flow)
        assert_same(text, rendering=False)
        assert_same(text, rendering=True)
        if not isinstance(outcome(text, False, rendering=False), tuple):
            assert read_fast(text, "scene.yaml", False) == parse_scene(text, "scene.yaml", False, fast=False)


def test_a_long_line_outside_the_subset_is_refused_in_linear_time():
    text = "cgamesh: 1\nsurfaces: a" + " " * 200_000 + "b\n"
    assert read_fast(text, "scene.yaml", False) is None


# --- the subset's parser alone, against PyYAML's node tree ---------------------------------------

def _careful_plain(text: str):
    """(the document as the careful reader composes it, as plain data with the fast path's
    conventions, the number of keys written): a list item's mapping holds its line under "",
    a repeated key keeps its first place and its last value (as JSON's reading does); None if
    PyYAML refuses the text or a key is not a string."""
    import yaml

    from cgamesh.inputs.scene_yaml import CoreLoader, core_value

    keys = 0

    def plain(node, item=False):
        nonlocal keys
        if isinstance(node, yaml.MappingNode):
            out = {"": node.start_mark.line + 1} if item else {}
            for key_node, value_node in node.value:
                key = plain(key_node)
                if not isinstance(key, str) or key == "":
                    raise KeyError(key)
                out[key] = plain(value_node)
                keys += 1
            return out
        if isinstance(node, yaml.SequenceNode):
            return [plain(value, True) for value in node.value]
        return core_value(node)

    try:
        return plain(yaml.compose(text, Loader=CoreLoader)), keys
    except (yaml.YAMLError, KeyError, ValueError, TypeError, RecursionError):
        return None


SCALARS = ["0", "-0", "1", "12", "-3.5", "1e5", "1E-5", "2.5e+3", "1.", ".5", "+1", "01", "0x1F",
           "1_000", "true", "True", "TRUE", "false", "null", "Null", "~", "yes", "on", "x", "e5",
           "s_1", "a b", "a: b", "a:b", "NaN", ".inf", "-.inf", ".nan", "1e400", "-", "--", "?"]
FLOWS = ["[1, 2, 3]", "[1,2,3]", "[ 1, 2 ]", "[1, 2,]", "[]", "[1], [2]", "[[1, 2], [3, 4]]",
         "{a: 1, b: [1, 2]}", "{a: 1, a: 2}", "{a:1}", "{a: 1,b: 2}", "{ a: 1}", "{}", "{a: {b: 1}}",
         "{a: [[1, 2, 3], [4, 5, 6]]}", "[true, 1]", "[1, x]", "{a: 1} x", "[1, 2", "{a: 1, b: 2} # c"]
line = st.tuples(st.sampled_from(["", "  ", "    ", "   ", "      "]),
                 st.sampled_from(["", "", "- ", "-  ", "- - "]),
                 st.sampled_from(["", "a", "b", "c", "center"]),
                 st.sampled_from(["", ""] + SCALARS + FLOWS),
                 st.sampled_from(["", "", " # note", "  ", "#x"]))


def _text(lines) -> str:
    out = []
    for indent, dash, key, value, tail in lines:
        body = f"{key}:{' ' + value if value else ''}" if key else value
        out.append(f"{indent}{dash}{body}{tail}")
    return "\n".join(out) + "\n"


@settings(max_examples=600)
@given(st.lists(line, min_size=1, max_size=12))
def test_the_subset_parser_reads_what_pyyaml_reads_or_steps_aside(lines):
    from cgamesh.inputs.scene_subset import plain_document

    text = _text([("", "", "a", "", "")] + lines)  # a mapping at the top, like a scene
    fast = plain_document(text)  # (document, keys written): a repeated key shows in the count
    if fast is not None:
        assert repr(fast) == repr(_careful_plain(text)), text
