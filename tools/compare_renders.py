#!/usr/bin/env python3
"""Rays per path, rays per second and MSE x spp of glint-render builds or options, compared in one run.

    /usr/bin/python3 tools/compare_renders.py --scene cornell --size 96 --spp 64 \\
        --run before=../old/build/examples/glint-render:"--roulette spectral" \\
        --run after=./build/examples/glint-render:"" --reps 3

Each --run is NAME=BINARY:FLAGS. The runs alternate (rep 1 of every run, then rep 2, ...),
single-threaded and pinned to one core (taskset -c 1 where available), with camera rays
through pixel centres (light transport's error, as bench_convergence measures it). MSE is
measured against a reference rendered once by the first run's binary (--ref-spp, two
threads, another seed), minus the reference's own variance (from its variance layer); MSE x
spp is the per-sample error, so time x MSE at equal error compares as seconds/spp x MSE x spp.
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import exr  # noqa: E402


def render(binary, flags, scene, size, spp, out, seed, threads):
    cmd = [binary, "--scene", scene, "--size", str(size), "--spp", str(spp), "--threads", str(threads),
           "--pixel-centres", "--seed", str(seed), "--out", out] + flags.split()
    if threads == 1 and shutil.which("taskset"):
        cmd = ["taskset", "-c", "1"] + cmd
    text = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    m = re.search(r"in ([0-9.]+) s .*?([0-9.]+) Mrays/s, ([0-9]+) rays", text)
    if not m:
        raise RuntimeError(f"unexpected glint-render output: {text}")
    seconds, rays = float(m.group(1)), int(m.group(3))
    channels = exr.read_exr(out)
    return seconds, rays, exr.rgb_of(channels), exr.rgb_of(channels, "variance")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", default="cornell")
    ap.add_argument("--size", type=int, default=96)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--ref-spp", type=int, default=2048)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--run", action="append", required=True, help="NAME=BINARY:FLAGS")
    args = ap.parse_args()
    runs = []
    for r in args.run:
        name, rest = r.split("=", 1)
        binary, _, flags = rest.partition(":")
        if not os.access(binary, os.X_OK):
            sys.exit(f"compare_renders: {binary} is not an executable")
        runs.append((name, binary, flags))
    tmp = tempfile.mkdtemp(prefix="glint_compare_")
    _, _, ref, ref_var = render(runs[0][1], "", args.scene, args.size, args.ref_spp, f"{tmp}/ref.exr", 0x5eed, 2)
    ref_noise = ref_var.mean()
    stats = {name: [] for name, _, _ in runs}
    for rep in range(args.reps):
        for name, binary, flags in runs:
            s, rays, img, var = render(binary, flags, args.scene, args.size, args.spp, f"{tmp}/{name}.exr", rep + 1, 1)
            mse = max(((img - ref) ** 2).mean() - ref_noise, 0.0)
            stats[name].append((s, rays, mse, var.mean()))
    paths = args.size * args.size * args.spp
    print(f"{args.scene} {args.size}x{args.size}, {args.spp} spp, pixel centres, 1 thread, {args.reps} alternating reps; "
          f"reference {args.ref_spp} spp (its variance {ref_noise:.3g} subtracted)")
    print(f"{'run':<12} {'rays/path':>10} {'Mrays/s':>8} {'s/spp':>8} {'MSE*spp':>9} {'var*spp':>9} {'MSE*time':>10}")
    base = None
    for name, _, _ in runs:
        a = np.array(stats[name])
        s, rays, mse, var = a[:, 0].mean(), a[:, 1].mean(), a[:, 2].mean(), a[:, 3].mean()
        cost = mse * s
        base = base or cost
        print(f"{name:<12} {rays / paths:10.2f} {rays / s * 1e-6:8.2f} {s / args.spp:8.4f} {mse * args.spp:9.4f} "
              f"{var * args.spp:9.4f} {cost / base:9.3f}x")
    shutil.rmtree(tmp)


if __name__ == "__main__":
    main()
