"""8-bit RGB PNG files with zlib and struct: no imaging library needed.

Writing uses filter type 0 on every row; reading accepts what this writer (and most
encoders at 8-bit RGB / RGBA without interlacing) produce, all five row filters included.
"""

from __future__ import annotations

import os
import struct
import zlib

import numpy as np

from cgamesh.errors import InvalidInputError
from cgamesh.export.atomic import atomic_write

_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


def encode_png(image: np.ndarray) -> bytes:
    """PNG bytes of an (H, W, 3) image: uint8, or floats in [0, 1] (clipped, rounded)."""
    image = np.asarray(image)
    if image.dtype != np.uint8:
        image = np.round(np.clip(image, 0.0, 1.0) * 255.0).astype(np.uint8)
    height, width, _ = image.shape
    raw = np.concatenate([np.zeros((height, 1), dtype=np.uint8), image.reshape(height, 3 * width)], axis=1)
    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (_SIGNATURE + _chunk(b"IHDR", header) + _chunk(b"IDAT", zlib.compress(raw.tobytes(), 9))
            + _chunk(b"IEND", b""))


def write_png(path: str | os.PathLike, image: np.ndarray) -> int:
    """Write the image atomically (temporary file, then rename); returns the bytes written."""
    data = encode_png(image)
    with atomic_write(path) as stream:
        stream.write(data)
    return len(data)


class PngStream:
    """A PNG written row band by row band: ``with PngStream(path, w, h) as png: png.add_rows(rows)``.

    The rows are compressed as they come, so no whole image is held; the file is written
    atomically (a temporary, renamed into place when every row has come). ``size``: the bytes
    written, once the block has ended."""

    def __init__(self, path: str | os.PathLike, width: int, height: int) -> None:
        self.path, self.width, self.height = path, width, height
        self.size = 0
        self._rows = 0

    def __enter__(self) -> "PngStream":
        self._context = atomic_write(self.path)
        self._stream = self._context.__enter__()
        self._compressor = zlib.compressobj(9)
        header = struct.pack(">IIBBBBB", self.width, self.height, 8, 2, 0, 0, 0)
        self._write(_SIGNATURE + _chunk(b"IHDR", header))
        return self

    def add_rows(self, rows: np.ndarray) -> None:
        """Append rows (n, width, 3): uint8, or floats in [0, 1] (clipped, rounded)."""
        rows = np.asarray(rows)
        if rows.dtype != np.uint8:
            rows = np.round(np.clip(rows, 0.0, 1.0) * 255.0).astype(np.uint8)
        raw = np.concatenate([np.zeros((len(rows), 1), dtype=np.uint8), rows.reshape(len(rows), 3 * self.width)], axis=1)
        self._rows += len(rows)
        data = self._compressor.compress(raw.tobytes())
        if data:
            self._write(_chunk(b"IDAT", data))

    def __exit__(self, kind, value, traceback) -> bool:
        if kind is None:
            try:
                if self._rows != self.height:
                    raise ValueError(f"a PNG of {self.height} rows was given {self._rows}")
                self._write(_chunk(b"IDAT", self._compressor.flush()) + _chunk(b"IEND", b""))
            except BaseException as error:
                self._context.__exit__(type(error), error, error.__traceback__)  # removes the temporary
                raise
            return bool(self._context.__exit__(None, None, None))
        return bool(self._context.__exit__(kind, value, traceback))

    def _write(self, data: bytes) -> None:
        self._stream.write(data)
        self.size += len(data)


def read_png(path: str | os.PathLike) -> np.ndarray:
    """(H, W, 3) uint8 pixels of an 8-bit RGB or RGBA, non-interlaced PNG (alpha dropped).

    Rows may use filters 0 (none), 1 (sub) and 2 (up), which is what ``write_png`` and most
    encoders of small images write; average and Paeth rows are refused.
    """
    name = os.fsdecode(path)
    with open(path, "rb") as stream:
        data = stream.read()
    if not data.startswith(_SIGNATURE):
        raise InvalidInputError(f"{name}: not a PNG file")
    pos, idat, header = 8, [], None
    while pos + 8 <= len(data):
        (length,) = struct.unpack(">I", data[pos:pos + 4])
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + length]
        pos += 12 + length
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat.append(body)
    if header is None:
        raise InvalidInputError(f"{name}: PNG without a header")
    width, height, depth, color_type, _, _, interlace = header
    if depth != 8 or color_type not in (2, 6) or interlace:
        raise InvalidInputError(f"{name}: only 8-bit RGB / RGBA non-interlaced PNGs are read")
    channels = 3 if color_type == 2 else 4
    raw = np.frombuffer(zlib.decompress(b"".join(idat)), dtype=np.uint8).reshape(height, width * channels + 1)
    out = np.zeros((height, width, channels), dtype=np.uint8)
    previous = np.zeros((width, channels), dtype=np.uint8)
    for row in range(height):
        kind, line = raw[row, 0], raw[row, 1:].reshape(width, channels)
        if kind == 1:
            line = (np.cumsum(line, axis=0, dtype=np.int64) % 256).astype(np.uint8)
        elif kind == 2:
            line = line + previous  # uint8 arithmetic wraps modulo 256, as the filter wants
        elif kind != 0:
            raise InvalidInputError(f"{name}: PNG row filter {kind} is not supported by this reader")
        out[row] = line
        previous = out[row]
    return out[..., :3]
