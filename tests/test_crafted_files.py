"""A corpus of crafted, malformed mesh files through ``cgamesh check`` and ``cgamesh verify``.

The corpus is generated here, from a GLB the exporter writes for a small example: each case
breaks one thing (the GLB container, the JSON, an accessor, a buffer view, a buffer's URI,
the node graph, the values), and a few OBJ / PLY / STL / USD files do the same for the other
readers. Each file goes through both commands as a subprocess, under a time limit and an
address-space limit, and must end in exit status 2 (or 1, where the file is well formed and
only its quality fails) with exactly one line on stderr that names the file, and no
traceback.
"""

from __future__ import annotations

import base64
import copy
import json
import os
import resource
import struct
import subprocess
import sys
import tempfile
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest

from cgamesh_cli.main import main

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "examples" / "fig08_linear.yaml"
TIMEOUT = 60  # seconds per command: a hang fails the test instead of stalling it
ADDRESS_SPACE = 3 << 30  # bytes of address space per command: a runaway allocation dies early
MEMORY_BOUND = 1 << 30  # bytes of resident memory no command may exceed


# --- building files --------------------------------------------------------------------------------

def glb_bytes(document: dict, binary: bytes | None, version: int = 2) -> bytes:
    """A GLB container: header, JSON chunk (space-padded), optional BIN chunk (zero-padded)."""
    text = json.dumps(document).encode()
    text += b" " * (-len(text) % 4)
    body = struct.pack("<II", len(text), 0x4E4F534A) + text
    if binary is not None:
        binary += b"\0" * (-len(binary) % 4)
        body += struct.pack("<II", len(binary), 0x004E4942) + binary
    return struct.pack("<4sII", b"glTF", version, 12 + len(body)) + body


def split_glb(data: bytes) -> tuple[dict, bytes]:
    length = struct.unpack_from("<I", data, 12)[0]
    document = json.loads(data[20:20 + length])
    size = struct.unpack_from("<I", data, 20 + length)[0]
    return document, data[28 + length:28 + length + size]


@dataclass
class Case:
    """One crafted file. ``make(folder) -> path`` writes it; ``check`` / ``verify``: the exit
    statuses allowed (None: the command is not run on it)."""

    name: str
    make: object
    check: set = field(default_factory=lambda: {2})
    verify: set | None = field(default_factory=lambda: {2})


CASES: list[Case] = []


def case(name: str, check=None, verify=None, skip_verify: bool = False):
    def register(make):
        CASES.append(Case(name, make, check or {2}, None if skip_verify else (verify or {2})))
        return make
    return register


class Base:
    """The exporter's GLB of the example, as (document, binary), and helpers to vary it."""

    data: bytes = b""

    @classmethod
    def parts(cls) -> tuple[dict, bytes]:
        document, binary = split_glb(cls.data)
        return copy.deepcopy(document), binary

    @classmethod
    def write(cls, folder: Path, name: str, edit=None, binary_edit=None) -> Path:
        document, binary = cls.parts()
        if edit is not None:
            edit(document)
        if binary_edit is not None:
            binary = binary_edit(bytearray(binary))
        path = folder / name
        path.write_bytes(glb_bytes(document, bytes(binary)))
        return path

    @classmethod
    def gltf_with_uri(cls, folder: Path, uri: str, name: str = "external.gltf") -> Path:
        """A .gltf whose buffer is the external ``uri`` (and a true copy of it beside it)."""
        document, binary = cls.parts()
        (folder / "beside.bin").write_bytes(binary)
        document["buffers"][0]["uri"] = uri
        path = folder / name
        path.write_text(json.dumps(document))
        return path


def put(path: Path, content: bytes | str) -> Path:
    """Write a file and return its path."""
    if isinstance(content, str):
        path.write_text(content)
    else:
        path.write_bytes(content)
    return path


def accessor_of(document: dict, attribute: str) -> dict:
    primitive = document["meshes"][0]["primitives"][0]
    index = primitive["indices"] if attribute == "indices" else primitive["attributes"][attribute]
    return document["accessors"][index]


def set_float(offset: int, value: float):
    def edit(binary: bytearray) -> bytes:
        struct.pack_into("<f", binary, offset, value)
        return bytes(binary)
    return edit


# The container and the JSON.
case("empty file")(lambda f: put(f / "empty.glb", b"") or f / "empty.glb")
case("truncated GLB")(lambda f: put(f / "truncated.glb", Base.data[:len(Base.data) // 2]) or f / "truncated.glb")
case("GLB header declares more bytes")(
    lambda f: put(f / "long.glb", Base.data[:8] + struct.pack("<I", len(Base.data) + 100) + Base.data[12:])
    or f / "long.glb")
case("GLB version 1")(lambda f: put(f / "v1.glb", glb_bytes(*Base.parts(), version=1)) or f / "v1.glb")
case("JSON chunk length past the end")(
    lambda f: put(f / "chunk.glb", Base.data[:12] + struct.pack("<I", 10**6) + Base.data[16:])
    or f / "chunk.glb")
case("first chunk is BIN")(
    lambda f: put(f / "binfirst.glb", Base.data[:16] + struct.pack("<I", 0x004E4942) + Base.data[20:])
    or f / "binfirst.glb")
case("bad magic")(lambda f: put(f / "magic.glb", b"glTX" + Base.data[4:]) or f / "magic.glb")
case("JSON not UTF-8")(lambda f: put(f / "latin.gltf", b'{"asset": {"version": "2.0\xff"}}') or f / "latin.gltf")
case("JSON syntax error")(lambda f: put(f / "syntax.gltf", '{"asset": {"version": "2.0"},') or f / "syntax.gltf")
case("JSON is an array")(lambda f: put(f / "array.gltf", "[1, 2, 3]") or f / "array.gltf")
case("JSON is a number")(lambda f: put(f / "number.gltf", "42") or f / "number.gltf")
case("asset version 1.0")(lambda f: Base.write(f, "version.glb", lambda d: d["asset"].update(version="1.0")))
case("no asset")(lambda f: Base.write(f, "noasset.glb", lambda d: d.pop("asset")))
case("NaN literal in the JSON")(
    lambda f: put(f / "nan.gltf", '{"asset": {"version": "2.0"}, "nodes": [{"translation": [NaN, 0, 0]}]}')
    or f / "nan.gltf")
case("JSON nested 100000 deep")(
    lambda f: put(f / "deep.gltf", '{"asset": {"version": "2.0"}, "extras": ' + "[" * 100000 + "]" * 100000 + "}")
    or f / "deep.gltf")
case("accessors is not an array")(lambda f: Base.write(f, "accessors.glb", lambda d: d.update(accessors={})))
case("BIN chunk shorter than the buffer")(
    lambda f: Base.write(f, "shortbin.glb", lambda d: d["buffers"][0].update(byteLength=d["buffers"][0]["byteLength"] + 400)))

# Accessors and buffer views.
case("negative count")(lambda f: Base.write(f, "negative.glb", lambda d: accessor_of(d, "POSITION").update(count=-5)))
case("huge count")(lambda f: Base.write(f, "huge.glb", lambda d: accessor_of(d, "POSITION").update(count=10**12)))
case("zero count")(lambda f: Base.write(f, "zero.glb", lambda d: accessor_of(d, "POSITION").update(count=0)))
case("count is a string")(lambda f: Base.write(f, "string.glb", lambda d: accessor_of(d, "POSITION").update(count="28")))
case("unknown component type")(
    lambda f: Base.write(f, "component.glb", lambda d: accessor_of(d, "POSITION").update(componentType=5000)))
case("float indices")(lambda f: Base.write(f, "floatidx.glb", lambda d: accessor_of(d, "indices").update(componentType=5126)))
case("signed byte indices")(
    lambda f: Base.write(f, "signedidx.glb", lambda d: accessor_of(d, "indices").update(componentType=5120)))
case("POSITION of type VEC2")(lambda f: Base.write(f, "vec2.glb", lambda d: accessor_of(d, "POSITION").update(type="VEC2")))
case("accessor offset past its view")(
    lambda f: Base.write(f, "offset.glb", lambda d: accessor_of(d, "NORMAL").update(byteOffset=400)))
case("misaligned accessor offset")(
    lambda f: Base.write(f, "misaligned.glb", lambda d: accessor_of(d, "NORMAL").update(byteOffset=1)))
case("buffer view offset past its buffer")(
    lambda f: Base.write(f, "viewoffset.glb", lambda d: d["bufferViews"][1].update(byteOffset=10**6)))
case("buffer view length past its buffer")(
    lambda f: Base.write(f, "viewlength.glb", lambda d: d["bufferViews"][3].update(byteLength=10**6)))
case("buffer view of a missing buffer")(lambda f: Base.write(f, "viewbuffer.glb", lambda d: d["bufferViews"][0].update(buffer=3)))
case("accessor of a missing buffer view")(
    lambda f: Base.write(f, "accview.glb", lambda d: accessor_of(d, "NORMAL").update(bufferView=99)))
case("accessor without a buffer view")(
    lambda f: Base.write(f, "noview.glb", lambda d: accessor_of(d, "NORMAL").pop("bufferView")))
case("stride smaller than an element")(lambda f: Base.write(f, "stride4.glb", lambda d: d["bufferViews"][0].update(byteStride=4)))
case("stride over 252")(lambda f: Base.write(f, "stride300.glb", lambda d: d["bufferViews"][0].update(byteStride=300)))
case("count times stride past the view")(
    lambda f: Base.write(f, "strided.glb", lambda d: d["bufferViews"][0].update(byteStride=24)))
case("attribute names a missing accessor")(
    lambda f: Base.write(f, "attr99.glb", lambda d: d["meshes"][0]["primitives"][0]["attributes"].update(POSITION=99)))
case("sparse accessor")(
    lambda f: Base.write(f, "sparse.glb", lambda d: accessor_of(d, "POSITION").update(
        sparse={"count": 1, "indices": {"bufferView": 3, "componentType": 5123}, "values": {"bufferView": 0}})))
case("max that lies")(lambda f: Base.write(f, "maxlie.glb", lambda d: accessor_of(d, "POSITION").update(max=[9.0, 9.0, 9.0])))
case("normalized float accessor")(
    lambda f: Base.write(f, "normfloat.glb", lambda d: accessor_of(d, "POSITION").update(normalized=True)))
case("index out of range")(
    lambda f: Base.write(f, "index.glb", binary_edit=lambda b: bytes(b[:896] + struct.pack("<H", 1000) + b[898:])))
case("missing indices")(lambda f: Base.write(f, "noindices.glb", lambda d: d["meshes"][0]["primitives"][0].pop("indices")))
case("index count not a multiple of 3")(lambda f: Base.write(f, "idx107.glb", lambda d: accessor_of(d, "indices").update(count=107)))
case("lines, not triangles")(lambda f: Base.write(f, "lines.glb", lambda d: d["meshes"][0]["primitives"][0].update(mode=1)))
case("no POSITION")(
    lambda f: Base.write(f, "noposition.glb", lambda d: d["meshes"][0]["primitives"][0]["attributes"].pop("POSITION")))
case("attributes of different counts")(lambda f: Base.write(f, "counts.glb", lambda d: accessor_of(d, "NORMAL").update(count=27)))
case("no primitives")(lambda f: Base.write(f, "noprims.glb", lambda d: d["meshes"][0].update(primitives=[])))
case("material index out of range")(
    lambda f: Base.write(f, "material.glb", lambda d: d["meshes"][0]["primitives"][0].update(material=7)))
case("doubleSided not a boolean")(lambda f: Base.write(f, "double.glb", lambda d: d["materials"][0].update(doubleSided="yes")))

# Values.
case("NaN position")(lambda f: Base.write(f, "nanpos.glb", binary_edit=set_float(5 * 12, float("nan"))))
case("signalling NaN position")(
    lambda f: Base.write(f, "snan.glb", binary_edit=lambda b: bytes(b[:24] + struct.pack("<I", 0x7F800001) + b[28:])))
case("infinite normal")(lambda f: Base.write(f, "infnormal.glb", binary_edit=set_float(336 + 12, float("inf"))))


def _zero_normal(binary: bytearray) -> bytes:
    binary[336 + 24:336 + 36] = bytes(12)
    return bytes(binary)


# A well-formed file whose quality fails: check --strict says 1; verify has no direction to trace.
case("zero normal", check={1})(lambda f: Base.write(f, "zeronormal.glb", binary_edit=_zero_normal))

# URIs.
case("uri ../ outside the folder")(lambda f: Base.gltf_with_uri(f / "inner", "../outside.bin"))
case("uri %2e%2e/ outside the folder")(lambda f: Base.gltf_with_uri(f / "inner", "%2e%2e/outside.bin"))
case("absolute uri")(lambda f: Base.gltf_with_uri(f / "inner", str(f / "outside.bin")))
case("file:// uri")(lambda f: Base.gltf_with_uri(f / "inner", (f / "outside.bin").as_uri()))
case("http uri")(lambda f: Base.gltf_with_uri(f / "inner", "http://127.0.0.1:9/x.bin"))
case("backslash uri")(lambda f: Base.gltf_with_uri(f / "inner", "..\\outside.bin"))
case("uri of a missing file")(lambda f: Base.gltf_with_uri(f / "inner", "missing.bin"))
case("uri of a folder")(lambda f: (f / "inner" / "sub").mkdir() or Base.gltf_with_uri(f / "inner", "sub"))
case("uri of a FIFO")(lambda f: os.mkfifo(f / "inner" / "pipe.bin") or Base.gltf_with_uri(f / "inner", "pipe.bin"))
case("uri of a symlink to /dev/zero")(
    lambda f: os.symlink("/dev/zero", f / "inner" / "zero.bin") or Base.gltf_with_uri(f / "inner", "zero.bin"))
case("uri of a symlink leaving the folder")(
    lambda f: os.symlink(f / "outside.bin", f / "inner" / "link.bin") or Base.gltf_with_uri(f / "inner", "link.bin"))
case("data uri not base64")(lambda f: Base.gltf_with_uri(f / "inner", "data:application/octet-stream,abc"))
case("data uri invalid base64")(lambda f: Base.gltf_with_uri(f / "inner", "data:application/octet-stream;base64,@@@@"))
case("data uri shorter than the buffer")(
    lambda f: Base.gltf_with_uri(f / "inner", "data:application/octet-stream;base64," + base64.b64encode(b"abcd").decode()))
case("mesh file is a FIFO")(lambda f: os.mkfifo(f / "pipe.glb") or f / "pipe.glb")
case("mesh file is /dev/zero through a symlink")(lambda f: os.symlink("/dev/zero", f / "devzero.glb") or f / "devzero.glb")
case("mesh file is a folder")(lambda f: (f / "folder.glb").mkdir() or f / "folder.glb")


# The node graph.
def _cycle(document: dict, through: int) -> None:
    document["nodes"].append({"children": [0]})
    document["nodes"][0]["children"] = [len(document["nodes"]) - 1] if through else [0]


case("node that is its own child")(lambda f: Base.write(f, "selfchild.glb", lambda d: _cycle(d, 0)))
case("two-node cycle")(lambda f: Base.write(f, "cycle.glb", lambda d: _cycle(d, 1)))
case("cycle no scene reaches")(
    lambda f: Base.write(f, "hidden.glb", lambda d: d["nodes"].extend([{"children": [2]}, {"children": [1]}])))


def _deep_chain_with_cycle(document: dict) -> None:
    count = 50000
    document["nodes"] += [{"children": [len(document["nodes"]) + k + 1]} for k in range(count)]
    document["nodes"][-1]["children"] = [len(document["nodes"]) - count]  # the chain's last node closes it


case("50000-node chain closed into a cycle")(lambda f: Base.write(f, "chain.glb", _deep_chain_with_cycle))
case("node with two parents")(
    lambda f: Base.write(f, "parents.glb", lambda d: d["nodes"].extend([{"children": [0]}, {"children": [0]}])))
case("node mesh out of range")(lambda f: Base.write(f, "nodemesh.glb", lambda d: d["nodes"][0].update(mesh=5)))
case("node matrix of 15 numbers")(lambda f: Base.write(f, "matrix15.glb", lambda d: d["nodes"][0].update(matrix=[1.0] * 15)))
case("scene index out of range")(lambda f: Base.write(f, "scene.glb", lambda d: d.update(scene=4)))
case("scene root that is a child")(
    lambda f: Base.write(f, "rootchild.glb", lambda d: (d["nodes"].append({"children": [0]}),
                                                        d["scenes"][0]["nodes"].append(0))))

# The other readers (check only: verify reads glTF).
case("OBJ with a NaN vertex", skip_verify=True)(
    lambda f: put(f / "nan.obj", "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n") or f / "nan.obj")
case("OBJ that is a FIFO", skip_verify=True)(lambda f: os.mkfifo(f / "pipe.obj") or f / "pipe.obj")
case("PLY that is /dev/zero through a symlink", skip_verify=True)(
    lambda f: os.symlink("/dev/zero", f / "zero.ply") or f / "zero.ply")
case("PLY with a broken header", skip_verify=True)(
    lambda f: put(f / "broken.ply", b"ply\nformat binary_little_endian 1.0\nelement vertex 99999999999\nend_header\n")
    or f / "broken.ply")
case("STL that is a folder", skip_verify=True)(lambda f: (f / "folder.stl").mkdir() or f / "folder.stl")
case("USD text that is not USD", skip_verify=True)(lambda f: put(f / "garbage.usda", "#usda 1.0\n(((\n") or f / "garbage.usda")
case("USD sublayer outside the folder", skip_verify=True)(
    lambda f: put(f / "inner" / "sub.usda", '#usda 1.0\n(\n    subLayers = [@../outside.usda@]\n)\n')
    or f / "inner" / "sub.usda")
case("USD sublayer that is a FIFO", skip_verify=True)(
    lambda f: os.mkfifo(f / "inner" / "pipe.usda") or put(f / "inner" / "fifo.usda", 
        '#usda 1.0\n(\n    subLayers = [@pipe.usda@]\n)\n') or f / "inner" / "fifo.usda")
case("USD mesh with an index out of range", skip_verify=True)(
    lambda f: put(f / "index.usda", 
        '#usda 1.0\ndef Mesh "m"\n{\n    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]\n'
        '    int[] faceVertexCounts = [3]\n    int[] faceVertexIndices = [0, 1, 7]\n}\n') or f / "index.usda")
case("USD mesh with a NaN point", skip_verify=True)(
    lambda f: put(f / "nan.usda", 
        '#usda 1.0\ndef Mesh "m"\n{\n    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, nan, 0)]\n'
        '    int[] faceVertexCounts = [3]\n    int[] faceVertexIndices = [0, 1, 2]\n}\n') or f / "nan.usda")
case("USD mesh with fewer indices than its counts ask", skip_verify=True)(
    lambda f: put(f / "short.usda", 
        '#usda 1.0\ndef Mesh "m"\n{\n    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]\n'
        '    int[] faceVertexCounts = [3, 3]\n    int[] faceVertexIndices = [0, 1, 2]\n}\n') or f / "short.usda")


# --- running them ----------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    """The base GLB (exported from the example) and a folder per case."""
    folder = tmp_path_factory.mktemp("corpus")
    base = folder / "base.glb"
    assert main([str(SCENE), "-o", str(base), "--around", "6", "--along", "4", "-q"]) == 0
    Base.data = base.read_bytes()
    document, binary = split_glb(Base.data)
    # The byte offsets the cases poke at: positions, normals, uvs, indices in that order.
    assert [v["byteOffset"] for v in document["bufferViews"]] == [0, 336, 672, 896]
    return folder


def _limits():
    resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_SPACE, ADDRESS_SPACE))


# Each command appends its own peak resident set (and its children's, e.g. the USD reader's) to
# PEAKS on exit: the pytest process's RUSAGE_CHILDREN would also count every other test's
# subprocesses, whatever ran before this module.
_PEAK_RECORDER = (
    "import atexit, os, resource, runpy, sys\n"
    "def record():\n"
    "    peak = max(resource.getrusage(who).ru_maxrss for who in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN))\n"
    "    with open(os.environ['CGAMESH_TEST_PEAKS'], 'a') as peaks:\n"
    "        peaks.write(f'{peak * 1024}\\n')\n"
    "atexit.register(record)\n"
    "sys.argv = ['cgamesh', *sys.argv[1:]]\n"
    "runpy.run_module('cgamesh_cli.main', run_name='__main__')\n"
)
PEAKS = Path(tempfile.mkdtemp(prefix="cgamesh-peaks-")) / "peaks.txt"


def run(command: list[str]) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT)] + sys.path), CGAMESH_TEST_PEAKS=str(PEAKS))
    return subprocess.run([sys.executable, "-c", _PEAK_RECORDER, *command], capture_output=True, text=True,
                          timeout=TIMEOUT, preexec_fn=_limits, env=env, errors="replace")


def assert_one_clean_line(result: subprocess.CompletedProcess, allowed: set, path: Path) -> None:
    output = result.stdout + result.stderr
    assert "Traceback" not in output, output
    assert result.returncode in allowed, (result.returncode, output)
    if result.returncode == 2:
        lines = result.stderr.splitlines()
        assert len(lines) == 1, result.stderr
        assert lines[0].startswith("cgamesh: error: ") and path.name in lines[0], lines[0]
    else:  # a quality failure: the report on stdout names the file and says what failed
        assert result.stderr == "" and path.name in result.stdout and "FAILED" in result.stdout, output


def test_the_corpus_is_large_enough():
    assert len([c for c in CASES if c.verify is not None]) >= 45


@pytest.mark.parametrize("crafted", CASES, ids=lambda c: c.name)
def test_a_crafted_file_gets_one_line(crafted, corpus, tmp_path):
    (tmp_path / "inner").mkdir()
    (tmp_path / "outside.bin").write_bytes(split_glb(Base.data)[1])
    (tmp_path / "outside.usda").write_text("#usda 1.0\n")
    path = Path(crafted.make(tmp_path))
    assert_one_clean_line(run(["check", "--strict", str(path)]), crafted.check, path)
    if crafted.verify is not None:
        assert_one_clean_line(run(["verify", str(SCENE), str(path), "-q"]), crafted.verify, path)


def test_no_command_grew_past_the_memory_bound(corpus):
    """Run after the corpus (pytest keeps file order): the largest resident set of any command."""
    peaks = [int(line) for line in PEAKS.read_text().split()]
    assert len(peaks) >= len(CASES)  # every check of the corpus recorded itself (verify too, mostly)
    largest = max(peaks)
    assert largest < MEMORY_BOUND, f"a command reached {largest / 2**20:.0f} MiB"


# --- what the reports say ---------------------------------------------------------------------------

def test_a_nan_position_is_reported_by_accessor_and_element(corpus, tmp_path):
    path = Base.write(tmp_path, "nan.glb", binary_edit=set_float(5 * 12, float("nan")))
    result = run(["check", str(path)])
    assert result.returncode == 2
    assert "accessors[0]" in result.stderr and "POSITION" in result.stderr and "element 5" in result.stderr
    assert "nan" in result.stderr.lower()


def test_a_zero_normal_fails_check(corpus, tmp_path, capsys):
    path = Base.write(tmp_path, "zero.glb", binary_edit=_zero_normal)
    assert main(["check", "--json", str(path)]) == 0  # without --strict: the report alone
    report = json.loads(capsys.readouterr().out)
    assert not report["passed"] and report["surfaces"][0]["non_unit_normals"] == 1
    assert any("non-unit normals" in line for line in report["failures"])
    assert main(["check", "--strict", "-q", str(path)]) == 1
    good = tmp_path / "good.glb"
    good.write_bytes(Base.data)
    assert main(["check", "--strict", "-q", str(good)]) == 0  # the untouched file passes


@pytest.mark.parametrize("flag", ["--max-aspect", "--min-angle", "--max-normal-deviation"])
@pytest.mark.parametrize("value", ["nan", "inf", "-inf"])
def test_non_finite_thresholds_are_refused(flag, value, corpus, tmp_path):
    good = tmp_path / "good.glb"
    good.write_bytes(Base.data)
    result = run(["check", "--strict", f"{flag}={value}", str(good)])
    assert result.returncode == 2 and "finite" in result.stderr and "Traceback" not in result.stderr


@pytest.mark.parametrize("flag", ["--max-angle", "--max-distance", "--max-missed"])
def test_verify_refuses_non_finite_thresholds(flag, corpus, tmp_path):
    good = tmp_path / "good.glb"
    good.write_bytes(Base.data)
    result = run(["verify", str(SCENE), str(good), flag, "nan"])
    assert result.returncode == 2 and "finite" in result.stderr


def test_the_untouched_base_passes_both_commands(corpus, tmp_path):
    good = tmp_path / "good.glb"
    good.write_bytes(Base.data)
    assert run(["check", "--strict", "-q", str(good)]).returncode == 0
    assert run(["verify", str(SCENE), str(good), "-q"]).returncode == 0


def test_a_gltf_with_its_buffer_beside_it_reads_like_the_glb(corpus, tmp_path):
    from cgamesh.readers.readback import read_gltf

    (tmp_path / "inner").mkdir()
    gltf = Base.gltf_with_uri(tmp_path / "inner", "beside%2Ebin")  # percent-encoding inside the folder is fine
    glb = tmp_path / "good.glb"
    glb.write_bytes(Base.data)
    a, b = read_gltf(gltf, world=True)[0], read_gltf(glb, world=True)[0]
    np.testing.assert_array_equal(a.positions, b.positions)
    np.testing.assert_array_equal(a.faces, b.faces)


# --- random damage ----------------------------------------------------------------------------------

from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(flips=st.lists(st.tuples(st.integers(0, 10**6), st.integers(0, 255)), min_size=1, max_size=8),
       cut=st.one_of(st.none(), st.integers(0, 10**6)))
def test_randomly_damaged_glbs_read_or_fail_with_one_line(flips, cut, corpus, tmp_path):
    """Bytes overwritten anywhere (header, JSON, binary) and the file cut short: both readers
    either read it or raise the one-line error, never anything else."""
    from cgamesh.errors import CgameshError
    from cgamesh.readers.readback import read_gltf
    from cgamesh.tracer.meshfile import read_glb

    data = bytearray(Base.data)
    for where, value in flips:
        data[where % len(data)] = value
    if cut is not None:
        data = data[:cut % len(data)]
    path = tmp_path / "damaged.glb"
    path.write_bytes(bytes(data))
    for read in (lambda: read_gltf(path), lambda: read_gltf(path, world=True), lambda: read_glb(path, "z", 1.0)):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error")  # a warning would be a second line on stderr
                meshes = read()
        except CgameshError as error:
            message = str(error)
            assert "\n" not in message and str(path) in message, message
        else:
            for mesh in meshes:
                assert np.isfinite(mesh.positions).all() and np.isfinite(mesh.normals).all()
                assert len(mesh.faces) == 0 or 0 <= mesh.faces.min() <= mesh.faces.max() < len(mesh.positions)


@pytest.mark.parametrize("library", ["/dev/zero", "../outside.mtl", "pipe.mtl", "zero.mtl", "file:///etc/passwd"])
def test_an_obj_naming_a_forbidden_material_file_reads_without_it(library, tmp_path):
    """trimesh reads what an OBJ names through our resolver: nothing outside the folder, no
    FIFO, no device; the material is then missing, which trimesh tolerates, and the mesh reads."""
    from cgamesh.readers.readback import read_trimesh

    folder = tmp_path / "inner"
    folder.mkdir()
    os.mkfifo(folder / "pipe.mtl")
    os.symlink("/dev/zero", folder / "zero.mtl")
    (tmp_path / "outside.mtl").write_text("newmtl a\nKd 1 0 0\n")
    path = put(folder / "t.obj", f"mtllib {library}\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nusemtl a\nf 1//1 2//1 3//1\n")
    result = run(["check", "-q", str(path)])
    assert result.returncode == 0 and result.stderr == ""
    mesh = read_trimesh(path)[0]
    np.testing.assert_array_equal(mesh.faces, [[0, 1, 2]])
    np.testing.assert_allclose(mesh.normals, [[0.0, 0.0, 1.0]] * 3)


@pytest.fixture(scope="module")
def crate(tmp_path_factory):
    """The example exported as a USD crate file (.usdc)."""
    path = tmp_path_factory.mktemp("crate") / "base.usdc"
    assert main([str(SCENE), "-o", str(path), "--around", "6", "--along", "4", "-q"]) == 0
    return path.read_bytes()


def test_damaged_crate_files_get_one_line(crate, tmp_path):
    """usd-core aborts (SIGABRT) or stalls on some damaged crate files; the child process
    that reads them takes the blow, and check still ends in one line."""
    rng = np.random.default_rng(1)
    for trial in range(12):
        data = bytearray(crate)
        for _ in range(rng.integers(1, 6)):
            data[rng.integers(len(data))] = rng.integers(256)
        path = put(tmp_path / f"damaged{trial}.usdc", bytes(data))
        result = run(["check", "-q", str(path)])
        assert "Traceback" not in result.stderr and result.returncode in (0, 2), result.stderr
        if result.returncode == 2:
            assert len(result.stderr.splitlines()) == 1 and path.name in result.stderr


def test_a_usd_read_that_does_not_finish_is_one_line(crate, tmp_path, monkeypatch):
    from cgamesh.readers import usd_sandbox

    monkeypatch.setattr(usd_sandbox, "USD_SECONDS", 0.01)
    path = put(tmp_path / "slow.usdc", crate)
    with pytest.raises(usd_sandbox.UnreadableFileError, match="did not finish reading it within"):
        usd_sandbox.read_usd(path)


def test_a_usd_file_read_in_the_child_is_the_file(crate, tmp_path):
    from cgamesh.readers.readback import read_usd, read_usd_here

    path = put(tmp_path / "good.usdc", crate)
    here, child = read_usd_here(path), read_usd(path)
    assert [m.name for m in here] == [m.name for m in child]
    for a, b in zip(here, child):
        for field in ("positions", "normals", "uvs", "faces"):
            np.testing.assert_array_equal(getattr(a, field), getattr(b, field))


# --- the read limit follows --max-memory --------------------------------------------------------------

def test_the_read_limit_is_the_budget_when_one_is_given():
    from cgamesh.budget import FIXED_OVERHEAD
    from cgamesh.readers.files import MAX_FILE_BYTES, read_limit

    assert read_limit() == MAX_FILE_BYTES  # no --max-memory: the readers' own default
    assert read_limit(40 << 20) == read_limit("40M") == 40 << 20
    assert read_limit("5G") == 5 << 30  # above the default too: the budget decides
    assert read_limit(1024) == FIXED_OVERHEAD  # never below what every budget allows


def test_check_and_verify_reads_follow_max_memory(corpus, tmp_path):
    """A .gltf whose buffer file is 48 MiB (the mesh, then a sparse tail of zeros): read under the
    default limit, refused before it is read under --max-memory 40M, in one line naming the
    buffer file and the knob."""
    gltf = Base.gltf_with_uri(tmp_path, "beside.bin")
    big = 48 << 20
    os.truncate(tmp_path / "beside.bin", big)
    document = json.loads(gltf.read_text())
    document["buffers"][0]["byteLength"] = big
    gltf.write_text(json.dumps(document))
    assert run(["check", "--strict", "-q", str(gltf)]).returncode == 0
    assert run(["verify", str(SCENE), str(gltf), "-q"]).returncode == 0
    for command in (["check", str(gltf), "--max-memory", "40M"],
                    ["verify", str(SCENE), str(gltf), "-q", "--max-memory", "40M"]):
        result = run(command)
        assert_one_clean_line(result, {2}, gltf)
        assert "beside.bin" in result.stderr and f"{big} bytes" in result.stderr
        assert "more than the 40 MiB a read may take (--max-memory)" in result.stderr
    # A budget above the file's size reads it.
    assert run(["check", "--strict", "-q", str(gltf), "--max-memory", "64M"]).returncode == 0
