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
import os
import subprocess
import sys
import tempfile
from collections import defaultdict

from convergence_table import fmt, load, ratio  # the same CSV reading and ratio as docs/claims.md's table


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--bench', default='./build/benchmarks/bench_convergence')
    ap.add_argument('--seeds', type=int, nargs='+', default=[0, 1, 2, 3])
    ap.add_argument('--samplers', nargs='+', default=['random', 'halton', 'halton-owen', 'halton-cp'])
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
                cols['s'].append(ratio(d, scene, 'spectral', 'classic'))
                cols['e'].append(ratio(d, scene, 'estimate', 'classic'))
                # Across runs: this configuration's method against PCG classic of the same seed.
                both = {**d, (scene, 'pcg-classic'): base[(scene, 'classic')]}
                cols['ac'].append(ratio(both, scene, 'classic', 'pcg-classic'))
                cols['as'].append(ratio(both, scene, 'spectral', 'pcg-classic'))
                cols['t'].append(sum(p[1] for p in d[(scene, 'classic')]) / sum(p[1] for p in base[(scene, 'classic')]))
            row = lambda v: ', '.join(fmt(x) for x in v)
            print(f"| {scene} | {sampler} | {row(cols['s'])} | {row(cols['e'])} | {row(cols['ac'])} | "
                  f"{row(cols['as'])} | {row(cols['t'])} |")
    print(f'\nseeds {args.seeds}; CSVs in {work}')


if __name__ == '__main__':
    main()
