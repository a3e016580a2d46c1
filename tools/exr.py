"""Minimal OpenEXR reader for glint's tools (no PyPI: only numpy and zlib).

Reads single-part scanline files with NONE, ZIPS or ZIP compression and half, float or uint
channels: what glint-render writes (ZIP) and what Blender writes with ZIP compression.

    channels = read_exr("cornell.exr")       # {"R": array(h, w), ..., "variance.R": ...}
    rgb = rgb_of(channels)                   # array(h, w, 3)
    rgb = rgb_of(channels, "variance")       # the variance layer
"""
import struct
import zlib

import numpy as np

_TYPES = {0: np.dtype("<u4"), 1: np.dtype("<f2"), 2: np.dtype("<f4")}
_LINES = {0: 1, 2: 1, 3: 16}  # lines per chunk: NONE, ZIPS, ZIP


def _header(data):
    if data[:4] != b"\x76\x2f\x31\x01":
        raise ValueError("not an OpenEXR file")
    if data[4] != 2 or data[5] & 0x1a:  # tiled, deep or multi-part (0x04, long names, is fine: Blender sets it)
        raise ValueError("only single-part scanline OpenEXR files are supported")
    pos, attrs = 8, {}
    while data[pos] != 0:
        name_end = data.index(b"\0", pos)
        type_end = data.index(b"\0", name_end + 1)
        name = data[pos:name_end].decode()
        (size,) = struct.unpack_from("<i", data, type_end + 1)
        attrs[name] = data[type_end + 5:type_end + 5 + size]
        pos = type_end + 5 + size
    return attrs, pos + 1


def _channels(raw):
    out, pos = [], 0
    while raw[pos] != 0:
        end = raw.index(b"\0", pos)
        (ptype,) = struct.unpack_from("<i", raw, end + 1)
        out.append((raw[pos:end].decode(), _TYPES[ptype]))
        pos = end + 17
    return out


def _unzip(block):
    t = np.frombuffer(zlib.decompress(block), dtype=np.uint8).astype(np.int32)
    t = ((np.cumsum(t - 128) + 128) % 256).astype(np.uint8)  # undo the predictor: t[i] += t[i-1] - 128
    half = (len(t) + 1) // 2
    out = np.empty_like(t)
    out[0::2], out[1::2] = t[:half], t[half:]
    return out.tobytes()


def read_exr(path):
    """Returns {channel name: float64 array of shape (height, width)}."""
    with open(path, "rb") as f:
        data = f.read()
    attrs, pos = _header(data)
    xmin, ymin, xmax, ymax = struct.unpack("<4i", attrs["dataWindow"])
    w, h = xmax - xmin + 1, ymax - ymin + 1
    compression = attrs["compression"][0]
    if compression not in _LINES:
        raise ValueError(f"{path}: compression {compression} is not supported (NONE, ZIPS, ZIP)")
    chans = _channels(attrs["channels"])
    lines = _LINES[compression]
    chunks = (h + lines - 1) // lines
    offsets = struct.unpack_from(f"<{chunks}Q", data, pos)
    out = {name: np.empty((h, w)) for name, _ in chans}
    for off in offsets:
        y, size = struct.unpack_from("<ii", data, off)
        block = data[off + 8:off + 8 + size]
        n = min(lines, ymax + 1 - y)
        expected = n * w * sum(t.itemsize for _, t in chans)
        raw = block if size == expected or compression == 0 else _unzip(block)
        at = 0
        for row in range(n):
            for name, t in chans:
                out[name][y - ymin + row] = np.frombuffer(raw, dtype=t, count=w, offset=at)
                at += w * t.itemsize
    return out


def rgb_of(channels, layer=""):
    """The R, G, B channels of `layer` ("" for the main image) as an (h, w, 3) array."""
    prefix = layer + "." if layer else ""
    return np.stack([channels[prefix + c] for c in "RGB"], axis=-1)
