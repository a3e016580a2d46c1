"""Minimal OpenEXR reader for glint's tools (no PyPI: only numpy and zlib).

Reads single-part scanline files with NONE, ZIPS, ZIP or PIZ compression and half, float or
uint channels: what glint-render writes (ZIP), what Blender writes with ZIP compression, and
OpenEXR's default (PIZ). PIZ's Huffman decoding runs in Python: about a second per million
16-bit values.

    channels = read_exr("cornell.exr")       # {"R": array(h, w), ..., "variance.R": ...}
    rgb = rgb_of(channels)                   # array(h, w, 3)
    rgb = rgb_of(channels, "variance")       # the variance layer
"""
import struct
import zlib

import numpy as np

_TYPES = {0: np.dtype("<u4"), 1: np.dtype("<f2"), 2: np.dtype("<f4")}
_LINES = {0: 1, 2: 1, 3: 16, 4: 32}  # lines per chunk: NONE, ZIPS, ZIP, PIZ


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


# PIZ (OpenEXR's wavelet + Huffman compressor), decoded as OpenEXR's ImfPizCompressor.cpp
# and ImfHuf.cpp specify: a bitmap of the 16-bit values present and the Huffman-coded values
# (canonical code, run-length symbol), then per channel the inverse of a 2D Haar-like wavelet,
# then the bitmap's lookup table back to the original values.

def _huf_decode(data, n_out):
    im, i_max, _, n_bits = struct.unpack_from("<4I", data, 0)
    pos, bit, lengths = 20, 0, {}

    def bits(n):  # the next n bits, most significant first
        nonlocal pos, bit
        v = 0
        for _ in range(n):
            v = (v << 1) | ((data[pos] >> (7 - bit)) & 1)
            bit += 1
            if bit == 8:
                pos, bit = pos + 1, 0
        return v

    sym = im
    while sym <= i_max:  # the code lengths, 6 bits each, with runs of zeros
        length = bits(6)
        if length == 63:
            sym += bits(8) + 6
        elif length >= 59:
            sym += length - 59 + 2
        else:
            if length:
                lengths[sym] = length
            sym += 1
    if bit:
        pos, bit = pos + 1, 0
    count = [0] * 59  # canonical codes: longest first, as hufCanonicalCodeTable assigns them
    for length in lengths.values():
        count[length] += 1
    start, c = [0] * 59, 0
    for length in range(58, 0, -1):
        start[length], c = c, (c + count[length]) >> 1
    codes = {}
    for s in sorted(lengths):
        length = lengths[s]
        codes[(length, start[length])] = s
        start[length] += 1
    out = np.empty(n_out, dtype=np.uint16)
    stream = np.unpackbits(np.frombuffer(data, dtype=np.uint8, offset=pos)).tobytes()  # a byte 0 or 1 per bit
    n_bits = min(n_bits, len(stream))
    at, k, code, length = 0, 0, 0, 0
    while at < n_bits and k < n_out:
        code = (code << 1) | stream[at]
        at, length = at + 1, length + 1
        s = codes.get((length, code))
        if s is None:
            if length > 58:
                raise ValueError("PIZ: invalid Huffman code")
            continue
        if s == i_max:  # run-length symbol: the previous value, 8 bits of repeat count
            run = int.from_bytes(np.packbits(np.frombuffer(stream, dtype=np.uint8, count=8, offset=at)).tobytes(), "big")
            at += 8
            out[k:k + run] = out[k - 1]
            k += run
        else:
            out[k] = s
            k += 1
        code, length = 0, 0
    if k != n_out:
        raise ValueError(f"PIZ: {k} values decoded, expected {n_out}")
    return out


def _wdec(l, h, w14):
    if w14:
        ls = ((l.astype(np.int32) + 0x8000) & 0xFFFF) - 0x8000
        hs = ((h.astype(np.int32) + 0x8000) & 0xFFFF) - 0x8000
        ai = ls + (hs & 1) + (hs >> 1)
        return (ai & 0xFFFF).astype(np.uint16), ((ai - hs) & 0xFFFF).astype(np.uint16)
    m, d = l.astype(np.int64), h.astype(np.int64)
    b = (m - (d >> 1)) & 0xFFFF
    return ((d + b - 0x8000) & 0xFFFF).astype(np.uint16), b.astype(np.uint16)


def _wav2_decode(a, max_value):
    ny, nx = a.shape
    w14 = max_value < (1 << 14)
    n, p = min(nx, ny), 1
    while p <= n:
        p <<= 1
    p >>= 1
    p2, p = p, p >> 1
    while p >= 1:
        ry, rx = range(0, ny - p2 + 1, p2), range(0, nx - p2 + 1, p2)
        ey, ex = len(ry) * p2, len(rx) * p2  # the first row and column past the full 2x2 blocks
        y0, x0 = slice(0, ey, p2), slice(0, ex, p2)
        y1, x1 = slice(p, ey, p2), slice(p, ex, p2)
        i00, i10 = _wdec(a[y0, x0], a[y1, x0], w14)
        i01, i11 = _wdec(a[y0, x1], a[y1, x1], w14)
        a[y0, x0], a[y0, x1] = _wdec(i00, i01, w14)
        a[y1, x0], a[y1, x1] = _wdec(i10, i11, w14)
        if nx & p:  # the odd column
            a[y0, ex], a[y1, ex] = _wdec(a[y0, ex], a[y1, ex], w14)
        if ny & p:  # the odd row
            a[ey, x0], a[ey, x1] = _wdec(a[ey, x0], a[ey, x1], w14)
        p2, p = p, p >> 1


def _unpiz(block, w, n, chans):
    lo, hi = struct.unpack_from("<HH", block, 0)
    if hi >= 8192:
        raise ValueError("PIZ: bitmap out of range")
    bitmap = np.zeros(8192, dtype=np.uint8)
    pos = 4
    if lo <= hi:
        bitmap[lo:hi + 1] = np.frombuffer(block, dtype=np.uint8, count=hi - lo + 1, offset=pos)
        pos += hi - lo + 1
    present = np.unpackbits(bitmap, bitorder="little").astype(bool)
    present[0] = True
    lut = np.flatnonzero(present).astype(np.uint16)  # value k of the coded data is lut[k]
    (length,) = struct.unpack_from("<i", block, pos)
    sizes = [t.itemsize // 2 for _, t in chans]  # 16-bit words per value
    words = _huf_decode(block[pos + 4:pos + 4 + length], n * w * sum(sizes))
    planes, at = [], 0
    for size in sizes:
        plane = words[at:at + n * w * size].reshape(n, w * size)
        for j in range(size):
            comp = plane[:, j::size].copy()
            _wav2_decode(comp, len(lut) - 1)
            plane[:, j::size] = comp
        planes.append(lut[plane])
        at += n * w * size
    lines = [np.concatenate([p[row] for p in planes]) for row in range(n)]
    return np.concatenate(lines).astype("<u2").tobytes()


def read_exr(path):
    """Returns {channel name: float64 array of shape (height, width)}."""
    with open(path, "rb") as f:
        data = f.read()
    attrs, pos = _header(data)
    xmin, ymin, xmax, ymax = struct.unpack("<4i", attrs["dataWindow"])
    w, h = xmax - xmin + 1, ymax - ymin + 1
    compression = attrs["compression"][0]
    if compression not in _LINES:
        raise ValueError(f"{path}: compression {compression} is not supported (NONE, ZIPS, ZIP, PIZ)")
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
        if size == expected or compression == 0:
            raw = block
        elif compression == 4:
            raw = _unpiz(block, w, n, chans)
        else:
            raw = _unzip(block)
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
