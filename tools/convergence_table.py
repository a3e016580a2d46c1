#!/usr/bin/env python3
"""Prints docs/claims.md's table of 000's claims from one or more CSVs of bench_convergence.

    ./build/benchmarks/bench_convergence --scene all --threads 1 --csv docs/convergence.csv
    ./build/benchmarks/bench_convergence --scene all --threads 1 --sampler halton --csv docs/convergence_halton.csv
    ./build/benchmarks/bench_convergence --scene all --threads 1 --jitter --csv docs/convergence_jitter.csv
    python3 tools/convergence_table.py "random walks=docs/convergence.csv" \\
        "Halton walks=docs/convergence_halton.csv" "random, jittered pixels=docs/convergence_jitter.csv"

Each argument is LABEL=PATH (or PATH, labelled by itself) and gives one column of ratios.
Efficiency = 1 / (RMSE^2 * seconds); the ratio of a method to its baseline is the geometric
mean, over the spp levels >= 4, of the ratios at equal spp (as bench_convergence prints it).
The arealight summary lines (lowest RMSE, time overhead) are printed for each CSV.
"""
import csv
import math
import sys
from collections import defaultdict

CLAIMS = [
    # scene, method, baseline, claim in 000, target of the issue
    ('furnace', 'spectral', 'classic', '30-50% fewer samples (2.2)', '>= 1.3'),
    ('furnace', 'estimate', 'classic', '', ''),
    ('furnace', 'spectral+estimate', 'classic', '', ''),
    ('cornell', 'spectral', 'classic', '', ''),
    ('cornell', 'estimate', 'classic', 'about 30% (2.3)', '>= 1.2'),
    ('cornell', 'spectral+estimate', 'classic', '', ''),
    ('cornell-glossy', 'dis', 'mis', 'DIS ~ MIS (2.1, Fig. 2.1)', '~ 1'),
    ('cornell-glossy', 'w', 'mis', 'W worse (2.1, Fig. 2.1)', '< 1'),
    ('arealight', 'correlated', 'importance', '', ''),
    ('arealight', 'combined', 'importance', 'beats both at every spp (3.2)', 'see below'),
]


def load(path):
    data = defaultdict(list)
    with open(path) as f:
        for r in csv.DictReader(f):
            data[(r['scene'], r['method'])].append((int(r['spp']), float(r['seconds']), float(r['rmse'])))
    return data


def ratio(data, scene, m, b):
    pm, pb = data.get((scene, m), []), data.get((scene, b), [])
    logs = [math.log((pb_[2] ** 2 * pb_[1]) / (pm_[2] ** 2 * pm_[1]))
            for pm_, pb_ in zip(pm, pb) if pm_[0] >= 4]
    return math.exp(sum(logs) / len(logs)) if logs else None


def fmt(x):
    """Two decimals below 10; two significant digits above (the large ratios vary that much)."""
    if x < 10:
        return f'{x:.2f}'
    return f'{round(x, 1 - int(math.floor(math.log10(x)))):.0f}'


def main(args):
    runs = []
    for a in args or ['docs/convergence.csv']:
        label, _, path = a.rpartition('=')
        runs.append((label or path, load(path)))
    print('| scene | method | baseline | ' + ' | '.join(label for label, _ in runs) + ' | 000 | issue target |')
    print('|---|---|---|' + '---|' * len(runs) + '---|---|')
    for scene, m, b, claim, target in CLAIMS:
        cells = [ratio(data, scene, m, b) for _, data in runs]
        if all(c is None for c in cells):
            continue
        text = ' | '.join('-' if c is None else f'**{fmt(c)}**' for c in cells)
        print(f'| {scene} | {m} | {b} | {text} | {claim} | {target} |')
    print()
    for label, data in runs:
        imp, cor, com = (data.get(('arealight', k), []) for k in ('importance', 'correlated', 'combined'))
        if com and imp and cor:
            lower = sum(1 for a, b, c in zip(imp, cor, com) if c[2] < a[2] and c[2] < b[2])
            t = sum(c[1] for c in com) / sum(a[1] for a in imp) - 1
            print(f'arealight ({label}): combined has the lowest RMSE at {lower} of {len(com)} spp levels; '
                  f'its time overhead over importance sampling (10 light samples) is {100 * t:+.1f}%.')


if __name__ == '__main__':
    main(sys.argv[1:])
