"""OpenEXR without an imaging library: write a linear float target with per-pixel weights
(scanline, FLOAT, no compression) and read the server's renders (scanline, NONE/ZIPS/ZIP, HALF or
FLOAT), as the page does (web/exr.js). Pixels are flat lists, rows top to bottom."""
from __future__ import annotations

import itertools
import operator
import struct
import sys
import zlib
from array import array
from typing import Mapping, Sequence

_MAGIC = 20000630
_PIXEL_BYTES = {1: 2, 2: 4}  # HALF, FLOAT
_LINES_PER_CHUNK = {0: 1, 2: 1, 3: 16}  # NONE, ZIPS, ZIP


def exr_rgba(width: int, height: int, rgb: Sequence[float], weight: Sequence[float] | float = 1.0) -> bytes:
    """A target as EXR bytes: `rgb` linear (3 values a pixel), `weight` per pixel (or one for all)."""
    n = width * height
    if len(rgb) != 3 * n:
        raise ValueError(f"rgb holds {len(rgb)} values, {3 * n} expected for {width}x{height}")
    a = [float(weight)] * n if isinstance(weight, (int, float)) else list(weight)
    if len(a) != n:
        raise ValueError(f"weight holds {len(a)} values, {n} expected")
    return write_exr(width, height, {"R": rgb[0::3], "G": rgb[1::3], "B": rgb[2::3], "A": a})


def write_exr(width: int, height: int, channels: Mapping[str, Sequence[float]]) -> bytes:
    """A scanline EXR of FLOAT channels (each `width*height` values), no compression."""
    names = sorted(channels)  # the file lists channels alphabetically

    def attribute(name: str, kind: str, value: bytes) -> bytes:
        return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(value)) + value

    chlist = b"".join(c.encode() + b"\0" + struct.pack("<iB3xii", 2, 0, 1, 1) for c in names) + b"\0"
    window = struct.pack("<4i", 0, 0, width - 1, height - 1)
    header = struct.pack("<iI", _MAGIC, 2) + b"".join([
        attribute("channels", "chlist", chlist), attribute("compression", "compression", b"\0"),
        attribute("dataWindow", "box2i", window), attribute("displayWindow", "box2i", window),
        attribute("lineOrder", "lineOrder", b"\0"), attribute("pixelAspectRatio", "float", struct.pack("<f", 1)),
        attribute("screenWindowCenter", "v2f", struct.pack("<2f", 0, 0)), attribute("screenWindowWidth", "float", struct.pack("<f", 1)),
    ]) + b"\0"
    row_bytes = 4 * width * len(names)
    first = len(header) + 8 * height
    offsets = struct.pack(f"<{height}Q", *(first + y * (8 + row_bytes) for y in range(height)))
    columns = {c: array("f", channels[c]) for c in names}
    for c, values in columns.items():
        if len(values) != width * height:
            raise ValueError(f"channel {c} holds {len(values)} values, {width * height} expected")
    rows = []
    for y in range(height):
        data = b"".join(columns[c][y * width:(y + 1) * width].tobytes() for c in names)
        rows.append(struct.pack("<ii", y, row_bytes) + data)
    return header + offsets + b"".join(rows)


def read_exr(data: bytes) -> tuple[int, int, dict[str, list[float]]]:
    """(width, height, {channel: values}) of a scanline EXR."""
    magic, flags = struct.unpack_from("<iI", data, 0)
    if magic != _MAGIC:
        raise ValueError("not an OpenEXR file")
    if flags & 0x1200:
        raise ValueError("tiled or multi-part EXR: only scanline files are read")
    at, channels, compression, window = 8, [], None, None

    def text() -> str:
        nonlocal at
        end = data.index(b"\0", at)
        s = data[at:end].decode()
        at = end + 1
        return s

    while True:
        name = text()
        if not name:
            break
        text()
        (size,) = struct.unpack_from("<i", data, at)
        start = at = at + 4
        if name == "channels":
            while True:
                c = text()
                if not c:
                    break
                (kind,) = struct.unpack_from("<i", data, at)
                channels.append((c, kind))
                at += 16
        elif name == "compression":
            compression = data[start]
        elif name == "dataWindow":
            window = struct.unpack_from("<4i", data, start)
        at = start + size
    if compression not in _LINES_PER_CHUNK:
        raise ValueError(f"EXR compression {compression}: NONE, ZIPS and ZIP are read")
    x0, y0, x1, y1 = window
    width, height = x1 - x0 + 1, y1 - y0 + 1
    lines = _LINES_PER_CHUNK[compression]
    row_bytes = sum(width * _PIXEL_BYTES[k] for _, k in channels)
    out = {c: [0.0] * (width * height) for c, _ in channels}
    chunks = (height + lines - 1) // lines
    for k in range(chunks):
        (offset,) = struct.unpack_from("<Q", data, at + 8 * k)
        y, size = struct.unpack_from("<ii", data, offset)
        y -= y0
        n = min(lines, height - y)
        block = data[offset + 8: offset + 8 + size]
        if compression and size != n * row_bytes:
            block = _unzip(block)
        pos = 0
        for line in range(y, y + n):
            for c, kind in channels:
                step = _PIXEL_BYTES[kind]
                if kind == 2:  # FLOAT: straight from the bytes (little-endian, as EXR stores them)
                    values = array("f")
                    values.frombytes(block[pos:pos + 4 * width])
                    if sys.byteorder == "big":
                        values.byteswap()
                else:
                    values = struct.unpack_from(f"<{width}e", block, pos)
                out[c][line * width:(line + 1) * width] = values
                pos += width * step
    return width, height, out


try:  # Blender and Houdini ship numpy: the predictor below is a running sum over every byte
    import numpy as _np
except ImportError:  # the standard library alone: the same bytes, slower
    _np = None


_MINUS_128 = bytes((b - 128) & 0xFF for b in range(256))


def _unzip(block: bytes) -> bytes:
    """ZIP/ZIPS chunk: zlib, then the encoder's predictor and two-halves interleave undone."""
    raw = zlib.decompress(block)
    half = (len(raw) + 1) // 2
    if _np is not None:
        d = _np.frombuffer(raw, dtype=_np.uint8).copy()
        d[1:] -= 128  # wraps modulo 256, as the predictor does
        t = _np.cumsum(d, dtype=_np.uint8)
        out = _np.empty_like(t)
        out[0::2], out[1::2] = t[:half], t[half:]
        return out.tobytes()
    # The running sum in C: bytes less 128 (a translation table), summed by accumulate, cut to
    # a byte by map — no Python-level loop over the bytes.
    d = raw[:1] + raw[1:].translate(_MINUS_128)
    t = bytes(map((0xFF).__and__, itertools.accumulate(d, operator.add)))
    out = bytearray(len(t))
    out[0::2] = t[:half]
    out[1::2] = t[half:]
    return bytes(out)


def picture_of(channels: Mapping[str, Sequence[float]]) -> list[float]:
    """The picture a volstyle render's EXR shows (RGB + transmittance × background, interleaved
    RGB), as a solve reads it; a file without those layers gives its RGB."""
    n = len(channels["R"])
    rgb = [0.0] * (3 * n)
    for j, c in enumerate("RGB"):
        m, t, b = channels[c], channels.get("transmittance." + c), channels.get("background." + c)
        rgb[j::3] = [m[i] + (t[i] * b[i] if t and b else 0.0) for i in range(n)]
    return rgb
