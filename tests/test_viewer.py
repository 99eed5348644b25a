"""The viewer page: self-contained, loads in headless Chromium without errors, draws something.

Chromium runs with SwiftShader (software WebGL), so no GPU is needed. The page reports its
state in document.title ("cgamesh viewer: ready" / "...: error") and #status; console errors
are read from Chromium's log as well.
"""

from __future__ import annotations

import hashlib
import json
import re
import struct
import subprocess
import zlib
from pathlib import Path

import numpy as np
import pytest

from cgamesh_cli.main import main

ROOT = Path(__file__).resolve().parent.parent
ASSETS = ROOT / "cgamesh" / "viewer" / "assets"
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
         "--no-first-run", "--disable-extensions", "--window-size=900,600", "--virtual-time-budget=8000",
         "--enable-logging=stderr", "--v=0"]


def _run(chromium, page: Path, *extra: str, user_data: Path) -> subprocess.CompletedProcess:
    return subprocess.run([chromium, *FLAGS, f"--user-data-dir={user_data}", *extra, page.as_uri()],
                          capture_output=True, text=True, timeout=120, check=False)


def _png_pixels(data: bytes) -> np.ndarray:
    """(H, W, C) uint8 pixels of an 8-bit, non-interlaced RGB / RGBA PNG (what Chromium writes)."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, chunks, header = 8, [], None
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos: pos + 8])
        body = data[pos + 8: pos + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            chunks.append(body)
        pos += 12 + length
    width, height, depth, colour, _, _, interlace = header
    assert depth == 8 and colour in (2, 6) and interlace == 0, header
    channels = 3 if colour == 2 else 4
    raw = np.frombuffer(zlib.decompress(b"".join(chunks)), np.uint8).reshape(height, 1 + width * channels)
    out = np.zeros((height, width * channels), np.int32)
    for y in range(height):
        kind, line = raw[y, 0], raw[y, 1:].astype(np.int32)
        up = out[y - 1] if y else np.zeros_like(line)
        if kind == 0:
            out[y] = line
        elif kind == 2:
            out[y] = (line + up) & 255
        else:  # 1 (sub), 3 (average), 4 (Paeth) depend on the pixel to the left: go pixel by pixel
            row = np.zeros_like(line)
            for x in range(0, len(line), channels):
                left = row[x - channels: x] if x else np.zeros(channels, np.int32)
                corner = up[x - channels: x] if x else np.zeros(channels, np.int32)
                above = up[x: x + channels]
                if kind == 1:
                    pred = left
                elif kind == 3:
                    pred = (left + above) // 2
                else:
                    p = left + above - corner
                    pa, pb, pc = np.abs(p - left), np.abs(p - above), np.abs(p - corner)
                    pred = np.where((pa <= pb) & (pa <= pc), left, np.where(pb <= pc, above, corner))
                row[x: x + channels] = (line[x: x + channels] + pred) & 255
            out[y] = row
    return out.reshape(height, width, channels).astype(np.uint8)


@pytest.fixture(scope="module")
def pages(tmp_path_factory):
    folder = tmp_path_factory.mktemp("viewer")
    out = {}
    for stem in ("kb_tube", "ribbon_loop"):
        page = folder / f"{stem}.html"
        assert main(["view", str(ROOT / "examples" / f"{stem}.yaml"), "-o", str(page), "--around", "16",
                     "--along", "32", "-q"]) == 0
        out[stem] = page
    return out


def test_the_page_is_self_contained_and_carries_the_licences(pages):
    text = pages["kb_tube"].read_text()
    assert not re.search(r"""<(script|link|img)[^>]+(src|href)\s*=""", text), "no external resources"
    assert not re.search(r"""\b(src|href)\s*=\s*["']https?:""", text)
    assert "three.js 0.187.0" in text and "ganja.js 1.0.204" in text and text.count("MIT License") >= 2
    assert "Permission is hereby granted" in text
    data = json.loads(re.search(r'<script type="application/json" id="cgamesh-data">(.*?)</script>', text, re.S)[1])
    assert [s["name"] for s in data["surfaces"]] == ["kb_tube"]
    assert len(data["cga"]["controls"]) == 6 and len(data["cga"]["interpolated"]) > 0


def test_vendored_assets_match_their_manifest_and_pins():
    manifest = json.loads((ASSETS / "MANIFEST.json").read_text())
    for name, digest in manifest["sha256"].items():
        assert hashlib.sha256((ASSETS / name).read_bytes()).hexdigest() == digest, name
    pins = json.loads((ROOT / "tools" / "viewer" / "package.json").read_text())["dependencies"]
    for package in ("three", "ganja.js", "esbuild"):
        assert manifest["packages"][package]["version"] == pins[package]
    assert (ASSETS / "three.min.js").read_text().startswith("/*! three.js")
    assert (ASSETS / "ganja.min.js").read_text().startswith("/*! ganja.js")


@pytest.mark.parametrize("stem", ["kb_tube", "ribbon_loop"])
def test_the_page_loads_without_errors_and_draws_something(pages, chromium, tmp_path, stem):
    page = pages[stem]
    dom = _run(chromium, page, "--dump-dom", user_data=tmp_path / "dom")
    status = re.search(r'<pre id="status">(.*?)</pre>', dom.stdout, re.S)
    assert status and status[1] == "ready", (status[1] if status else dom.stdout[-2000:], dom.stderr[-3000:])
    assert "<title>cgamesh viewer: ready</title>" in dom.stdout
    console = [line for line in dom.stderr.splitlines() if "CONSOLE" in line and ("rror" in line or "Uncaught" in line)]
    assert console == [], console
    assert dom.stdout.count("<canvas") == 2, "three.js and ganja.js each drew into a canvas"

    shot = tmp_path / "shot.png"
    _run(chromium, page, f"--screenshot={shot}", user_data=tmp_path / "shot")
    pixels = _png_pixels(shot.read_bytes())[..., :3].astype(np.float64)
    assert pixels.shape[0] > 100 and pixels.shape[1] > 100
    # The mesh area (left of the CGA inset) is far from one flat colour.
    mesh_area = pixels[60:, : int(pixels.shape[1] * 0.6)]
    assert mesh_area.std(axis=(0, 1)).max() > 10.0
    distinct = len(np.unique((mesh_area // 8).reshape(-1, 3), axis=0))
    assert distinct > 20, "a lit mesh shades through many colours"
