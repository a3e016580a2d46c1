#!/usr/bin/env python3
"""Roulette efficiency ratios on the furnace and the Cornell box for every sampler and several
seeds, and each configuration's absolute efficiency against PCG classic of the same seed.

    python3 tools/roulette_samplers.py                 # about 5 minutes, one thread
    python3 tools/roulette_samplers.py --seeds 0 1 --samplers random halton-cp

Runs ./build/benchmarks/bench_convergence --scene S --threads 1 --sampler X --seed N for each
scene S (furnace, cornell), sampler X and seed N, into a scratch folder, and prints, per
configuration and seed, the ratios spectral/classic and estimate/classic (geometric mean over
spp >= 4 of the efficiency ratios at equal spp, as bench_convergence prints them), and the
efficiency of classic and spectral relative to PCG ("random") classic with the same seed, so
that a sampler's own cost shows: a ratio within a slow configuration is not a speed-up over
the fast one.
"""
import argparse
import csv
import math
import os
import subprocess
import sys
import tempfile
from collections import defaultdict


def load(path):
    data = defaultdict(list)
    with open(path) as f:
        for r in csv.DictReader(f):
            data[r['method']].append((int(r['spp']), float(r['seconds']), float(r['rmse'])))
    return data


def ratio(m, b):
    logs = [math.log((pb[2] ** 2 * pb[1]) / (pm[2] ** 2 * pm[1])) for pm, pb in zip(m, b) if pm[0] >= 4]
    return math.exp(sum(logs) / len(logs))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--bench', default='./build/benchmarks/bench_convergence')
    ap.add_argument('--seeds', type=int, nargs='+', default=[0, 1, 2, 3])
    ap.add_argument('--samplers', nargs='+', default=['random', 'halton', 'halton-cp', 'halton-perm'])
    ap.add_argument('--scenes', nargs='+', default=['furnace', 'cornell'])
    ap.add_argument('--from', dest='from_dir', help='print the table from the CSVs of an earlier run in DIR')
    args = ap.parse_args()
    samplers = ['random'] + [s for s in args.samplers if s != 'random']  # the absolute baseline first
    work = args.from_dir or tempfile.mkdtemp(prefix='glint_roulette_samplers_')
    runs = {}
    for scene in args.scenes:
        for seed in args.seeds:
            for sampler in samplers:
                path = os.path.join(work, f'{scene}_{sampler}_{seed}.csv')
                if args.from_dir:
                    runs[(scene, sampler, seed)] = load(path)
                    continue
                subprocess.run([args.bench, '--scene', scene, '--threads', '1', '--sampler', sampler, '--seed',
                                str(seed), '--csv', path, '--plot', os.path.join(work, 'unused.png')],
                               check=True, stdout=subprocess.DEVNULL)
                runs[(scene, sampler, seed)] = load(path)
                print(f'  ran {scene} {sampler} seed {seed}', file=sys.stderr)
    print('| scene | sampler | spectral / classic | estimate / classic | classic vs PCG classic | '
          'spectral vs PCG classic | time per sample vs PCG |')
    print('|---|---|---|---|---|---|---|')
    for scene in args.scenes:
        for sampler in samplers:
            cols = defaultdict(list)
            for seed in args.seeds:
                d, base = runs[(scene, sampler, seed)], runs[(scene, 'random', seed)]
                cols['s'].append(ratio(d['spectral'], d['classic']))
                cols['e'].append(ratio(d['estimate'], d['classic']))
                cols['ac'].append(ratio(d['classic'], base['classic']))
                cols['as'].append(ratio(d['spectral'], base['classic']))
                cols['t'].append(sum(p[1] for p in d['classic']) / sum(p[1] for p in base['classic']))
            fmt = lambda v: ', '.join(f'{x:.2f}' if x < 10 else f'{round(x, 1 - int(math.floor(math.log10(x)))):.0f}'
                                      for x in v)
            print(f"| {scene} | {sampler} | {fmt(cols['s'])} | {fmt(cols['e'])} | {fmt(cols['ac'])} | "
                  f"{fmt(cols['as'])} | {fmt(cols['t'])} |")
    print(f'\nseeds {args.seeds}; CSVs in {work}')


if __name__ == '__main__':
    main()
