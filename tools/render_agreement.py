#!/usr/bin/env python3
"""Whether two glint-render builds (or option sets) render the same image, within noise.

    /usr/bin/python3 tools/render_agreement.py --scene cornell --size 64 --spp 256 \\
        --run before=../old/build/examples/glint-render:"" --run after=./build/examples/glint-render:""

Each run renders once (its own seed), writing the image and its per-pixel variance layer (the
variance of the pixel's mean). Per pixel, z = (a - b) / sqrt(var_a + var_b); for two unbiased
renders of the same image z has mean 0 and, where the variance estimates are good, RMS near 1
(heavy-tailed pixels with few samples make the estimated variance low, so RMS a bit above 1 is
expected). Printed: the image mean per band of each run with its standard error, their
difference in standard errors, and the per-pixel z statistics. Exit status 1 when a band's
image means differ by more than 4 standard errors.
"""
import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import exr  # noqa: E402


def render(binary, flags, args, seed, out):
    cmd = [binary, "--scene", args.scene, "--size", str(args.size), "--spp", str(args.spp), "--threads",
           str(args.threads), "--seed", str(seed), "--out", out] + flags.split()
    text = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    channels = exr.read_exr(out)
    return exr.rgb_of(channels).astype(np.float64), exr.rgb_of(channels, "variance").astype(np.float64), text.strip()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scene", default="cornell")
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--run", action="append", required=True, help="NAME=BINARY:FLAGS (two of them)")
    args = ap.parse_args()
    if len(args.run) != 2:
        sys.exit("give exactly two --run NAME=BINARY:FLAGS")
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        for k, spec in enumerate(args.run):
            name, rest = spec.split("=", 1)
            binary, flags = rest.split(":", 1) if ":" in rest else (rest, "")
            img, var, text = render(binary, flags, args, 1000 + k, os.path.join(tmp, f"{name}.exr"))
            print(f"{name}: {text}")
            results.append((name, img, var))
    (na, a, va), (nb, b, vb) = results
    n = a.shape[0] * a.shape[1]
    worst = 0.0
    for c, band in enumerate("RGB"):
        ma, mb = a[..., c].mean(), b[..., c].mean()
        sa, sb = np.sqrt(va[..., c].sum()) / n, np.sqrt(vb[..., c].sum()) / n
        d = (ma - mb) / np.sqrt(sa**2 + sb**2)
        worst = max(worst, abs(d))
        print(f"  {band}: {na} {ma:.6f} +- {sa:.6f}, {nb} {mb:.6f} +- {sb:.6f}: difference {d:+.2f} standard errors")
    s = va + vb
    ok = s > 0
    z = (a - b)[ok] / np.sqrt(s[ok])
    same = np.count_nonzero((~ok) & (a == b))
    print(f"  per pixel and band ({z.size} with variance, {same} without and equal): mean z {z.mean():+.3f}, "
          f"RMS z {np.sqrt((z**2).mean()):.3f}, |z| > 3: {100.0 * np.mean(np.abs(z) > 3):.2f}%, "
          f"|z| > 5: {100.0 * np.mean(np.abs(z) > 5):.3f}%")
    print(f"  largest image-mean difference: {worst:.2f} standard errors ({'agree' if worst <= 4 else 'DIFFER'})")
    return 0 if worst <= 4 else 1


if __name__ == "__main__":
    sys.exit(main())
