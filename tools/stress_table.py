#!/usr/bin/env python3
"""Turns the CSV of stress_intersection into the Markdown table of docs/intersection.md.

    ./build/benchmarks/stress_intersection --csv stress.csv && python3 tools/stress_table.py stress.csv
"""
import csv
import sys

CATEGORIES = ['random', 'sliver', 'far-1e3', 'far-1e6', 'origin-plane', 'zero-area',
              'parallel', 'nonfinite', 'closed-mesh']


def percent(count, total):
    return f"{100.0 * count / total:.3g}%" if total else "-"


def main(path):
    rows = list(csv.DictReader(open(path)))
    table = {}
    for r in rows:
        table.setdefault((r['policy'], r['precision']), {})[r['category']] = r
    print('| policy | precision | ' + ' | '.join(CATEGORIES) + ' |')
    print('|' + '---|' * (2 + len(CATEGORIES)))
    for (policy, precision), by_cat in table.items():
        cells = []
        for c in CATEGORIES:
            r = by_cat[c]
            n, hits = int(r['cases']), int(r['reference_hits'])
            fm, fh, far = int(r['false_miss']), int(r['false_hit']), int(r['far_errors'])
            if c == 'closed-mesh':
                cells.append(f"**{percent(fm, n)}** leak")
            else:
                cell = f"{percent(fm, hits)} / {percent(fh, n - hits)}"
                cells.append(cell + (f" ({far} far)" if far else ""))
        print(f"| {policy} | {precision} | " + ' | '.join(cells) + ' |')


if __name__ == '__main__':
    main(sys.argv[1] if len(sys.argv) > 1 else 'stress.csv')
