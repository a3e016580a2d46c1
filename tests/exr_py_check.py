"""tools/exr.py on glint-render --aov's EXR (ZIP) and its PIZ rewrite by OpenEXR: both read,
every channel equal bit for bit, and the first-hit layers plausible (normals at most unit
length and unit inside walls, depth positive and +inf only where nothing was hit, albedo
within [0, 1]). Then random float and half channels, written here uncompressed and rewritten
with PIZ by OpenEXR (exr_stats): so many distinct values that PIZ takes its 16-bit wavelet,
where the render's layers take the 14-bit one; read back exactly.

    python3 tests/exr_py_check.py ZIP.exr PIZ.exr EXR_STATS SCRATCH_DIR
"""
import os
import struct
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tools"))
import numpy as np  # noqa: E402
import exr  # noqa: E402

zip_file, piz_file = sys.argv[1], sys.argv[2]
a, b = exr.read_exr(zip_file), exr.read_exr(piz_file)
assert sorted(a) == sorted(b), (sorted(a), sorted(b))
for name in a:
    assert np.array_equal(a[name], b[name]), f"{name} differs between ZIP and PIZ"
n = np.stack([a["normal." + c] for c in "XYZ"], axis=-1)
length = np.linalg.norm(n, axis=-1)
assert length.max() <= 1 + 1e-6, length.max()
assert np.mean(np.abs(length - 1) < 1e-6) > 0.5, "most pixels of the box lie inside one wall"
albedo = exr.rgb_of(a, "albedo")
assert (albedo >= 0).all() and (albedo <= 1).all()
missed = np.isinf(a["depth.Z"])  # every ray of the pixel left the open box: no albedo, no normal
assert (a["depth.Z"] > 0).all() and (length[missed] == 0).all() and (albedo[missed] == 0).all()
print(f"tools/exr.py: {len(a)} channels of {a['R'].shape[1]} x {a['R'].shape[0]} read from ZIP and PIZ, equal")


def write_uncompressed(path, channels):
    """A scanline EXR without compression: {name: float32 or float16 array (h, w)}."""
    names = sorted(channels)
    h, w = channels[names[0]].shape
    def attr(name, kind, value):
        return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(value)) + value
    chlist = b"".join(n.encode() + b"\0" + struct.pack("<iB3xii", 1 if channels[n].dtype == np.float16 else 2, 0, 1, 1)
                      for n in names) + b"\0"
    box = struct.pack("<4i", 0, 0, w - 1, h - 1)
    header = (b"\x76\x2f\x31\x01" + struct.pack("<i", 2) + attr("channels", "chlist", chlist) +
              attr("compression", "compression", b"\0") + attr("dataWindow", "box2i", box) +
              attr("displayWindow", "box2i", box) + attr("lineOrder", "lineOrder", b"\0") +
              attr("pixelAspectRatio", "float", struct.pack("<f", 1)) +
              attr("screenWindowCenter", "v2f", struct.pack("<2f", 0, 0)) +
              attr("screenWindowWidth", "float", struct.pack("<f", 1)) + b"\0")
    lines = [b"".join(channels[n][y].astype(channels[n].dtype.newbyteorder("<")).tobytes() for n in names) for y in range(h)]
    offset = len(header) + 8 * h
    offsets = []
    for line in lines:
        offsets.append(offset)
        offset += 8 + len(line)
    with open(path, "wb") as f:
        f.write(header + struct.pack(f"<{h}Q", *offsets))
        for y, line in enumerate(lines):
            f.write(struct.pack("<ii", y, len(line)) + line)


stats, scratch = sys.argv[3], sys.argv[4]
rng = np.random.default_rng(7)
# A last block of 13 lines, odd sizes for the wavelet's odd row and column. Random mantissas in
# R and B (over 16384 distinct 16-bit words in a block of 32 lines), smooth ramps in G and
# half.Y, so that PIZ still compresses (a block it cannot shrink is stored raw).
h, w = 45, 517
ramp = np.add.outer(np.arange(h) * 0.25, np.arange(w) / w)
noise = {"R": (1 + rng.random((h, w))).astype(np.float32), "G": ramp.astype(np.float32),
         "B": (1 + rng.random((h, w))).astype(np.float32), "half.Y": ramp.astype(np.float16)}
raw, piz = os.path.join(scratch, "exr_py_random.exr"), os.path.join(scratch, "exr_py_random_piz.exr")
write_uncompressed(raw, noise)
subprocess.run([stats, raw, piz, "piz"], check=True, stdout=subprocess.DEVNULL)
modes = []
wav2 = exr._wav2_decode
exr._wav2_decode = lambda a, m: (modes.append(m >= 1 << 14), wav2(a, m))[1]
for path in (raw, piz):
    back = exr.read_exr(path)
    assert sorted(back) == sorted(noise), sorted(back)
    for name, v in noise.items():
        assert np.array_equal(back[name], v.astype(np.float64)), f"{path}: {name} differs"
assert any(modes), "the 16-bit wavelet was not exercised"
print(f"tools/exr.py: random float and half channels, {w} x {h}, read exactly from NONE and PIZ (16-bit wavelet)")
