#!/usr/bin/env python3
"""Prints the README's table of 000's claims from the CSV of bench_convergence.

    ./build/benchmarks/bench_convergence --scene all --csv docs/convergence.csv
    python3 tools/convergence_table.py docs/convergence.csv

Efficiency = 1 / (RMSE^2 * seconds); the ratio of a method to its baseline is the geometric
mean, over the spp levels >= 4, of the ratios at equal spp (as bench_convergence prints it).
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


def main(path):
    data = defaultdict(list)
    for r in csv.DictReader(open(path)):
        data[(r['scene'], r['method'])].append((int(r['spp']), float(r['seconds']), float(r['rmse'])))

    def ratio(scene, m, b):
        pm, pb = data[(scene, m)], data[(scene, b)]
        logs = [math.log((pb_[2] ** 2 * pb_[1]) / (pm_[2] ** 2 * pm_[1]))
                for pm_, pb_ in zip(pm, pb) if pm_[0] >= 4]
        return math.exp(sum(logs) / len(logs)) if logs else float('nan')

    print('| scene | method | baseline | efficiency ratio | 000 | issue target |')
    print('|---|---|---|---|---|---|')
    for scene, m, b, claim, target in CLAIMS:
        if (scene, m) in data:
            print(f'| {scene} | {m} | {b} | **{ratio(scene, m, b):.2f}** | {claim} | {target} |')
    imp, cor, com = (data[('arealight', k)] for k in ('importance', 'correlated', 'combined'))
    if com:
        lower = sum(1 for a, b, c in zip(imp, cor, com) if c[2] < a[2] and c[2] < b[2])
        t = sum(c[1] for c in com) / sum(a[1] for a in imp) - 1
        print(f'\narealight: combined has the lowest RMSE at {lower} of {len(com)} spp levels; '
              f'its time overhead over importance sampling (10 light samples) is {100 * t:+.1f}% in this run.')


if __name__ == '__main__':
    main(sys.argv[1] if len(sys.argv) > 1 else 'docs/convergence.csv')
