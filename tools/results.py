#!/usr/bin/env python3
"""README's results table, as code: re-measure every row on this machine.

    bash tools/results.sh                  # full run: every row, writes docs/results.md and README's table
    bash tools/results.sh --quick          # smoke run (tiny sizes, CI): checks the pipeline, rewrites nothing
    bash tools/results.sh --rows cones,occluders   # some rows only (the others keep README's text)
    bash tools/results.sh --list           # the rows, their commands and rough full-run times

Every benchmark runs single-threaded, pinned with `taskset -c CORE` (--core, default 1), each
measurement repeated (--reps, default 3; seeds 0, 1, 2 where a benchmark takes a seed), and
the ratios are those the benchmark measures within one run. For each row the script prints
the number README states next to the measured one (median over the repetitions, and the
run-to-run spread, min-max over them), and flags it when the stated number lies outside the
spread widened by the stated number's rounding (stated 2.0 covers 1.95-2.05). A range
stated over scenes ("1.06-1.99") is compared end by end with the measured range's ends.

Only a full run (no --quick, no --rows) rewrites README's table (between the markers
`<!-- results:begin -->` and `<!-- results:end -->`) and docs/results.md; a partial run
writes build/results/partial.md. A row that could not be measured keeps README's text,
marked "not re-measured: <why>".

Each benchmark's output is parsed by one small function (parse_*), so that a change to a
benchmark's output changes one function.
"""
import argparse
import csv
import io
import json
import math
import os
import re
import resource
import shutil
import statistics
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BEGIN, END = '<!-- results:begin -->', '<!-- results:end -->'


# --------------------------------------------------------------------------- parsers
# One function per benchmark output. Each takes the text (or a file) a run wrote and returns
# plain dicts; a missing field raises ParseError, which marks the row "not re-measured".

class ParseError(Exception):
    pass


def need(value, what):
    if value is None or value == {} or value == []:
        raise ParseError('no ' + what + ' in the output')
    return value


def parse_bench_trees(text):
    """bench_trees --wide: {'ratio': {(scene, set): x Embree}, 'bytes': {scene: (glint B/tri,
    Embree B/tri)}, 'build': {scene: glint 1-thread build / Embree's}}."""
    ratio = {(m.group(1), m.group(2)): float(m.group(3))
             for m in re.finditer(r'^# best on (\S+)/(\S+): .*?, ([0-9.]+) x Embree', text, re.M)}
    bytes_, build = {}, {}
    for m in re.finditer(r'^# (\S+) bvh8 build: (.*)$', text, re.M):
        line = m.group(2)
        b = re.search(r'; ([0-9.]+) B/tri \(nodes.*?/ Embree x([0-9.]+)\), ([0-9.]+) B/tri', line)
        if b:
            bytes_[m.group(1)] = (float(b.group(1)), float(b.group(3)))
            build[m.group(1)] = float(b.group(2))
    return {'ratio': need(ratio, 'Embree ratio ("# best on ...")'), 'bytes': bytes_, 'build': build}


def parse_bench_trees_memory(text):
    """bench_trees --memory: {(scene, tree, K): saving of compact-K against havran-K, %}."""
    out = {}
    for m in re.finditer(r'^\|\s*(\S+)\s*\|\s*(kd|bih)\s*\|\s*(\d+)\s*\|(?:[^|]*\|){3}\s*([0-9.]+)%', text, re.M):
        out[(m.group(1), m.group(2), int(m.group(3)))] = float(m.group(4))
    return need(out, 'memory table')


def parse_bench_intersection(text):
    """bench_intersection's closing table: {benchmark: time ratio to Moller-Trumbore}."""
    tail = text.split('ratio to Moller-Trumbore', 1)
    if len(tail) < 2:
        raise ParseError('no ratio table')
    out = {m.group(1): float(m.group(3))
           for m in re.finditer(r'^(\S+)\s+([0-9.]+)\s+([0-9.]+)\s*$', tail[1], re.M)}
    return need(out, 'ratio rows')


def parse_bench_convergence(csv_path):
    """bench_convergence --csv: {scene: {method: [(spp, seconds, rmse)...]}}."""
    out = {}
    with open(csv_path) as f:
        for r in csv.DictReader(f):
            out.setdefault(r['scene'], {}).setdefault(r['method'], []).append(
                (int(r['spp']), float(r['seconds']), float(r['rmse'])))
    return need(out, 'rows in ' + csv_path)


def parse_bench_lambda(csv_path):
    """bench_lambda --csv: {(region, lambda, radius): row dict of floats}."""
    out = {}
    with open(csv_path) as f:
        for r in csv.DictReader(f):
            key = (r['region'], r['lambda'], r['radius'])
            out[key] = {k: float(v) for k, v in r.items() if re.fullmatch(r'[-+0-9.eE]+|nan|inf', v or '')}
    return need(out, 'rows in ' + csv_path)


def parse_bench_occluders(text):
    """bench_occluders: {scene: {spheres: (speedup over shadow rays, rel. RMSE)}} (linear scan)."""
    out, scene = {}, None
    for line in text.splitlines():
        m = re.match(r'== VPL render: (\S+) in a box', line)
        if m:
            scene = m.group(1)
            continue
        m = re.match(r'spheres-linear\s+(\d+)\s+[0-9.]+\s+([0-9.]+)\s+([0-9.]+)', line)
        if m and scene:
            out.setdefault(scene, {})[int(m.group(1))] = (float(m.group(2)), float(m.group(3)))
    return need(out, 'VPL render rows')


def parse_bench_cones(text):
    """bench_cones: {triangles: {'tiles': x brute, 'tiles_split': x brute, 'tree': x brute,
    'tree_vs_tiles': x}}."""
    out = {}
    for m in re.finditer(r'^# (\d+) triangles: tiles ([0-9.]+)x brute, tiles_split ([0-9.]+)x brute, '
                         r'tree ([0-9.]+)x brute, tree ([0-9.]+)x tiles', text, re.M):
        out[int(m.group(1))] = {'tiles': float(m.group(2)), 'tiles_split': float(m.group(3)),
                                'tree': float(m.group(4)), 'tree_vs_tiles': float(m.group(5))}
    return need(out, 'per-count ratio lines')


def parse_bench_photons(text):
    """bench_photons' kNN tables: {(photons, k): (glint / nanoflann speed, same distances)}."""
    out, photons = {}, None
    for line in text.splitlines():
        m = re.match(r'# kNN against nanoflann [\d.]+: (\d+) photons', line)
        if m:
            photons = int(m.group(1))
            continue
        m = re.match(r'\s+(\d+)\s+[\d.]+\s+[\d.]+\s+([\d.]+)\s+(yes|no)\s*$', line)
        if m and photons:
            out[(photons, int(m.group(1)))] = (float(m.group(2)), m.group(3) == 'yes')
    if not out:
        raise ParseError('no kNN table in bench_photons output')
    return out


def parse_bench_lights(csv_path):
    """bench_lights --csv: {scene: {method: [row dict of floats, one per repetition]}}."""
    out = {}
    with open(csv_path) as f:
        for r in csv.DictReader(f):
            vals = {k: float(v) for k, v in r.items() if k not in ('scene', 'method')}
            out.setdefault(r['scene'], {}).setdefault(r['method'], []).append(vals)
    return need(out, 'rows in ' + csv_path)


def parse_peer_cycles(json_path):
    """tools/peer_cycles.py --json: {(scene, spp): equal-error time ratio glint / Cycles (image)}."""
    with open(json_path) as f:
        data = json.load(f)
    out = {}
    for s in data:
        for r in s.get('ladder', []):
            out.setdefault((s['scene'], int(r['spp'])), []).append(float(r['ratio']))
    return need({k: statistics.median(v) for k, v in out.items()}, 'ladder rows')


# ---------------------------------------------------------------------- computations

def efficiency_ratio(m, base):
    """bench_convergence's definition: geometric mean over spp >= 4 of
    (1 / (MSE s)) / (1 / (MSE_base s_base)) at equal spp."""
    logs = [math.log((b[2] ** 2 * b[1]) / (x[2] ** 2 * x[1]))
            for x, b in zip(m, base) if x[0] >= 4 or m[-1][0] < 4]
    return math.exp(sum(logs) / len(logs))


def combined_lowest(methods, others):
    """(levels where 'combined' has the lowest RMSE, levels)."""
    com = methods['combined']
    low = sum(all(c[2] < methods[o][i][2] for o in others) for i, c in enumerate(com))
    return low, len(com)


def time_overhead(methods, m, base):
    return 100.0 * (sum(p[1] for p in methods[m]) / sum(p[1] for p in methods[base]) - 1.0)


# ----------------------------------------------------------------------------- jobs
# A job is one benchmark command; rows read jobs' parsed results, one result per repetition.

class Ctx:
    def __init__(self, a):
        self.a = a
        self.bin = os.path.join(a.build_dir, 'benchmarks')
        self.scenes = a.scenes
        self.work = os.path.join(a.build_dir, 'results')
        self.logs = os.path.join(self.work, 'logs-quick' if a.quick else 'logs')
        os.makedirs(self.logs, exist_ok=True)
        self.cache = {}
        self.times = {}
        self.reused = set()
        self.cpu = {}

    def mesh(self, name):
        p = os.path.join(self.scenes, name)
        return p if os.path.exists(p) else None

    def pinned(self, argv):
        return ['taskset', '-c', str(self.a.core)] + argv if shutil.which('taskset') else argv

    def run(self, name, argv, rep):
        """Runs argv once (pinned), keeps its output in the log folder, returns stdout. With
        --resume, a log of the same command that finished (exit 0) is read instead."""
        key = (name, rep)
        if key in self.cache:
            return self.cache[key]
        log = os.path.join(self.logs, '%s.%d.log' % (name, rep))
        command = '$ ' + ' '.join(argv)
        if self.a.resume and os.path.exists(log):
            text = open(log).read()
            m = re.search(r'\n# exit 0 after ([0-9.]+) s(?:, CPU ([0-9.]+) s)?\n$', text)
            if text.startswith(command + '\n') and m:
                print('results: reuse %-20s rep %d: %s' % (name, rep, log), flush=True)
                self.times[key] = float(m.group(1))
                if m.group(2):
                    self.cpu[key] = float(m.group(2))
                self.reused.add(key)
                self.cache[key] = text[len(command) + 1:m.start() + 1]
                return self.cache[key]
        t0 = time.time()
        u0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        print('results: run %-22s rep %d: %s' % (name, rep, ' '.join(argv)), flush=True)
        p = subprocess.run(self.pinned(argv), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                           cwd=self.work)
        self.times[key] = time.time() - t0
        u1 = resource.getrusage(resource.RUSAGE_CHILDREN)  # the process's user + system time
        self.cpu[key] = (u1.ru_utime - u0.ru_utime) + (u1.ru_stime - u0.ru_stime)
        with open(log, 'w') as f:
            f.write(command + '\n' + p.stdout + ('' if p.stdout.endswith('\n') else '\n'))
            f.write('# exit %d after %.1f s, CPU %.2f s\n' % (p.returncode, self.times[key], self.cpu[key]))
        if p.returncode != 0:
            raise RuntimeError('%s exited %d (log %s): %s' % (name, p.returncode, log, p.stdout[-400:].strip()))
        self.cache[key] = p.stdout
        return p.stdout

    def exe(self, name):
        p = os.path.join(self.bin, name)
        if not os.path.exists(p):
            raise RuntimeError('%s is not built (cmake --build %s --target %s)' % (p, self.a.build_dir, name))
        return p


def job_trees(c, rep):
    q = c.a.quick
    argv = [c.exe('bench_trees'), '--wide', '--few', '--cpu-time']
    if q:
        argv += ['--only', 'torus-knot', '--rays', '2000', '--reps', '1']
    else:
        argv += ['--big', '--rays', str(c.a.tree_rays), '--reps', '5']
        for m in ['bunny.obj', 'diplodocus.obj', 'turbine.obj', 'cornell_box.obj']:
            if c.mesh(m):
                argv += ['--mesh', c.mesh(m)]
    text = c.run('bench_trees', argv, rep)
    if 'Embree' not in text:
        raise Skip('bench_trees was built without Embree 3 (the peer): install it and rebuild')
    return parse_bench_trees(text)


def parse_bench_trees_user(text):
    """bench_trees --user-meshes: {(set, query, quality): geometric mean of Embree time / glint time}."""
    out = {(m.group(1), m.group(2), m.group(3)): float(m.group(4))
           for m in re.finditer(r'^# geomean (\S+) (\S+) Embree (\S+): ([0-9.]+) x', text, re.M)}
    # Hit-count disagreements (a ray or two on a grazing edge) are printed as DISAGREE rows, not hidden.
    return need(out, 'geometric means ("# geomean ...")')


def job_trees_user(c, rep, program='bench_trees'):
    """The shared meshes through MeshBvh's public calls: bench_user_meshes (one tree type in its
    unit, as a user's program) or bench_trees --user-meshes (the same rows in a unit of dozens of
    tree types, where GCC inlines otherwise)."""
    if not os.path.isdir(c.scenes):
        raise Skip('the shared meshes are not beside the repository (%s)' % c.scenes)
    mode, log = (['--user-meshes'], 'bench_trees_user') if program == 'bench_trees' else ([], program)
    argv = [c.exe(program)] + mode + ['--scenes', c.scenes]
    if c.a.quick:
        argv += ['--only', 'bunny', '--rays', '2000', '--primary', '32', '--reps', '1', '--no-generated']
    no_peer = Skip('%s was built without Embree 3 (the peer): install it and rebuild' % program)
    try:
        text = c.run(log, argv, rep)
    except RuntimeError as e:
        if 'needs Embree 3' in str(e):  # bench_user_meshes without its peer exits 1
            raise no_peer
        raise
    if 'Embree' not in text:
        raise no_peer
    return parse_bench_trees_user(text)


def job_memory(c, rep):
    argv = [c.exe('bench_trees'), '--memory']
    if not c.a.quick and c.mesh('bunny.obj'):
        argv += ['--mesh', c.mesh('bunny.obj')]
    return parse_bench_trees_memory(c.run('bench_trees_memory', argv, rep))


def job_intersection(c, rep):
    argv = [c.exe('bench_intersection')]
    if c.a.quick:
        argv += ['--benchmark_min_time=0.001', '--benchmark_repetitions=1']
    return parse_bench_intersection(c.run('bench_intersection', argv, rep))


def job_convergence(c, rep, scene, sampler='random', extra=()):
    name = 'bench_convergence_%s_%s' % (scene, sampler) + ''.join('_' + e.strip('-') for e in extra)
    out = os.path.join(c.logs, '%s.%d.csv' % (name, rep))
    argv = [c.exe('bench_convergence'), '--scene', scene, '--threads', '1', '--sampler', sampler,
            '--seed', str(rep), '--cache', os.path.join(c.work, 'cache'), '--csv', out, '--plot', out + '.png']
    argv += list(extra)
    if c.a.quick:
        argv += ['--quick']
    c.run(name, argv, rep)
    res = parse_bench_convergence(out)
    return res[scene]


def job_envmap(c, rep):
    extra = ('--size', '16', '--max-spp', '4') if c.a.quick else ('--size', '48', '--max-spp', '32')
    return job_convergence(c, rep, 'envmap', 'random', extra)


def job_lambda(c, rep, scene):
    name = 'bench_lambda_' + scene
    out = os.path.join(c.logs, '%s.%d.csv' % (name, rep))
    argv = [c.exe('bench_lambda'), '--scene', scene, '--seed', str(rep), '--csv', out]
    if c.a.quick:
        argv += ['--quick']
    c.run(name, argv, rep)
    return parse_bench_lambda(out)


def job_occluders(c, rep):
    argv = [c.exe('bench_occluders')]
    if c.a.quick:
        argv += ['--quick']
    elif c.mesh('bunny.obj'):
        argv += ['--mesh', c.mesh('bunny.obj')]
    return parse_bench_occluders(c.run('bench_occluders', argv, rep))


def job_cones(c, rep):
    argv = [c.exe('bench_cones')] + (['--quick', '--size', '32', '--counts', '100,5000'] if c.a.quick else [])
    return parse_bench_cones(c.run('bench_cones', argv, rep))


def job_lights(c, rep):
    out = os.path.join(c.logs, 'bench_lights.%d.csv' % rep)
    argv = [c.exe('bench_lights'), '--csv', out] + (['--quick'] if c.a.quick else [])
    c.run('bench_lights', argv, rep)
    return parse_bench_lights(out)


def job_photons(c, rep):
    argv = [c.exe('bench_photons'), '--knn-only'] + (['--quick'] if c.a.quick else [])
    return parse_bench_photons(c.run('bench_photons', argv, rep))


def job_cycles(c, rep):
    return peer_cycles(c, rep, 'cornell,cornell-bunny', 'peer_cycles', [])


def job_cycles_lights(c, rep):
    """The many-light scenes, glint with the light tree and the radiance-estimate roulette."""
    return peer_cycles(c, rep, 'hall,kitchen', 'peer_cycles_lights',
                       ['--size', '128', '--ref-spp', '2048', '--ladder', '64,256',
                        '--glint-args', '--direct tree --roulette estimate'])


def peer_cycles(c, rep, scenes, name, extra):
    if c.a.quick:
        raise Skip('--quick does not run Blender (a reference takes minutes)')
    blender = shutil.which('blender')
    if not blender:
        raise Skip('Blender is not installed (Debian: apt-get install blender)')
    render = os.path.join(c.a.build_dir, 'examples', 'glint-render')
    if not os.path.exists(render):
        raise Skip('glint-render is not built')
    out = os.path.join(c.logs, '%s.%d.json' % (name, rep))
    argv = [sys.executable, os.path.join(ROOT, 'tools', 'peer_cycles.py'), '--scenes', scenes,
            '--glint', render, '--core', str(c.a.core), '--json', out,
            '--work', os.path.join(c.a.build_dir, name)] + extra
    if c.mesh('bunny.obj'):
        argv += ['--bunny', c.mesh('bunny.obj')]
    c.run(name, argv, rep)  # peer_cycles pins its own renders
    return parse_peer_cycles(out)


class Skip(Exception):
    pass


def job_caustics(c, rep):
    """tools/caustics_table.py: {(budget, method): row} (RMSE against each renderer's own reference)."""
    if c.a.quick:
        raise Skip('--quick does not run Blender (a reference takes minutes)')
    if not shutil.which('blender'):
        raise Skip('Blender is not installed (Debian: apt-get install blender)')
    render = os.path.join(c.a.build_dir, 'examples', 'glint-render')
    if not os.path.exists(render):
        raise Skip('glint-render is not built')
    out = os.path.join(c.logs, 'caustics_table.%d.json' % rep)
    argv = [sys.executable, os.path.join(ROOT, 'tools', 'caustics_table.py'), '--glint', render, '--core', str(c.a.core),
            '--json', out, '--work', os.path.join(c.a.build_dir, 'caustics_table')]
    c.run('caustics_table', argv, rep)  # the script pins its own renders
    with open(out) as f:
        return {(r['budget'], r['method']): r for r in json.load(f)['rows']}


# ----------------------------------------------------------------------------- rows
# A row: README's "what" and "against" cells, the checks (item, stated value or range, how to
# get the value from one repetition's jobs), and the result cell written from the measured values.

class Check:
    def __init__(self, label, stated, get, fmt='%.2f', unit=''):
        self.label, self.stated, self.get, self.fmt, self.unit = label, stated, get, fmt, unit


def rng(values):
    values = list(values)
    if not values:
        raise ParseError('no values for a range')
    return (min(values), max(values))


def conv(c, rep, scene, sampler='random', extra=()):
    return job_convergence(c, rep, scene, sampler, tuple(extra))


ROWS = []


def row(key, what, against, stated_cell, reps, checks, cell, minutes):
    ROWS.append(dict(key=key, what=what, against=against, stated_cell=stated_cell, reps=reps, checks=checks,
                     cell=cell, minutes=minutes))


def cycles_ratio(scene, spp):
    return lambda c, r: job_cycles(c, r)[(scene, spp)]


row('cycles-cornell',
    'path tracer, equal-error time (MSE·time) on the Cornell box at 64 / 256 / 1024 spp',
    'Blender Cycles 3.4, same scene exported exactly',
    '**0.68 / 0.42 / 0.32** of Cycles\' time; regions agree within 0.13% '
    '([tracer.md](docs/tracer.md#peer-comparison-cycles))', 1,
    [Check('64 spp', '0.68', cycles_ratio('cornell', 64)), Check('256 spp', '0.42', cycles_ratio('cornell', 256)),
     Check('1024 spp', '0.32', cycles_ratio('cornell', 1024))],
    lambda m: '**%s / %s / %s** of Cycles\' time ([tracer.md](docs/tracer.md#peer-comparison-cycles))' % (
        m('64 spp'), m('256 spp'), m('1024 spp')), 15)
row('cycles-lights',
    'path tracer on the many-light hall (800 point and spot lights) and kitchen (72 disk lights), 64 / 256 spp, '
    '`--direct tree --roulette estimate`',
    'Cycles 3.4 (power light selection; its light tree came in 3.5)',
    '**0.018** (hall) and **0.15** (kitchen) of Cycles\' equal-error time; with power selection and the throughput '
    'roulette 0.25 and 0.53; references agree within noise ([lights.md](docs/lights.md#against-cycles))', 1,
    [Check('hall 64 spp', '0.018', lambda c, r: job_cycles_lights(c, r)[('hall', 64)], '%.3f'),
     Check('hall 256 spp', '0.018', lambda c, r: job_cycles_lights(c, r)[('hall', 256)], '%.3f'),
     Check('kitchen 64 spp', '0.15', lambda c, r: job_cycles_lights(c, r)[('kitchen', 64)]),
     Check('kitchen 256 spp', '0.15', lambda c, r: job_cycles_lights(c, r)[('kitchen', 256)])],
    lambda m: '**%s / %s** (hall) and **%s / %s** (kitchen) of Cycles\' equal-error time at 64 / 256 spp '
              '([lights.md](docs/lights.md#against-cycles))' % (
        m('hall 64 spp'), m('hall 256 spp'), m('kitchen 64 spp'), m('kitchen 256 spp')), 25)
row('cycles-bunny', 'the same, Cornell box with the Stanford bunny', 'Cycles 3.4',
    '**0.76 / 0.48 / 0.34**', 1,
    [Check('64 spp', '0.76', cycles_ratio('cornell-bunny', 64)),
     Check('256 spp', '0.48', cycles_ratio('cornell-bunny', 256)),
     Check('1024 spp', '0.34', cycles_ratio('cornell-bunny', 1024))],
    lambda m: '**%s / %s / %s**' % (m('64 spp'), m('256 spp'), m('1024 spp')), 15)


def trees_range(c, r):
    return rng(job_trees(c, r)['ratio'].values())


row('trees', 'wide BVH, closest hit, incoherent and primary rays, 8 scenes (36–2M triangles)',
    'Embree 3 `rtcIntersect1`, same rays',
    '**1.06–1.99×** Embree\'s throughput (medians of 3 runs; every row ≥ 1.03 in every run); 48–52 bytes per '
    'triangle against 108–144; one-thread build 0.04–1.48× Embree\'s time '
    '([trees.md](docs/trees.md#measured))',
    3,
    [Check('throughput ratio, range over scenes and ray sets', '1.06–1.99', trees_range, '%.2f', '×'),
     Check('glint bytes per triangle', '48–52', lambda c, r: rng(v[0] for v in job_trees(c, r)['bytes'].values()),
           '%.0f'),
     Check('Embree bytes per triangle', '108–144',
           lambda c, r: rng(v[1] for v in job_trees(c, r)['bytes'].values()), '%.0f'),
     Check('one-thread build / Embree', '0.04–1.48', lambda c, r: rng(job_trees(c, r)['build'].values()), '%.2f',
           '×')],
    lambda m: '**%s×** Embree\'s throughput (%s); %s bytes per triangle against %s; one-thread build %s× '
              'Embree\'s time ([trees.md](docs/trees.md#measured))' % (m('throughput ratio, range over scenes and ray sets'), m.spread_note(),
                                      m('glint bytes per triangle'), m('Embree bytes per triangle'),
                                      m('one-thread build / Embree')), 8)

def trees_user_check(label, stated, query, program):
    return Check(label, stated, lambda c, r: job_trees_user(c, r, program)[('shared', query, 'high')])


row('trees_user', 'MeshBvh (public API, defaults), every mesh of ../shared/scenes, geometric mean',
    'Embree 3 HIGH, FTZ/DAZ, `rtcIntersect1` / `rtcOccluded1`, same rays',
    '**1.19 / 1.47 / 1.32×** Embree HIGH\'s throughput (incoherent / primary / any hit, geometric mean)', 5,
    [trees_user_check('incoherent closest hit / Embree HIGH', '1.19', 'incoherent', 'bench_user_meshes'),
     trees_user_check('primary closest hit / Embree HIGH', '1.47', 'primary', 'bench_user_meshes'),
     trees_user_check('any hit / Embree HIGH', '1.32', 'shadow', 'bench_user_meshes'),
     trees_user_check('incoherent, bench_trees\' unit', '1.19', 'incoherent', 'bench_trees'),
     trees_user_check('primary, bench_trees\' unit', '1.47', 'primary', 'bench_trees'),
     trees_user_check('any hit, bench_trees\' unit', '1.32', 'shadow', 'bench_trees')],
    lambda m: '**%s / %s / %s×** Embree HIGH\'s throughput (incoherent / primary / any hit, geometric mean) in a '
              'program with one tree type, as a user\'s (bench_user_meshes); %s / %s / %s× in bench_trees, whose '
              'unit holds dozens of tree types ([trees.md](docs/trees.md#what-a-user-gets-the-twelve-shared-meshes-through-meshbvh))'
              % (m('incoherent closest hit / Embree HIGH'), m('primary closest hit / Embree HIGH'),
                 m('any hit / Embree HIGH'), m('incoherent, bench_trees\' unit'), m('primary, bench_trees\' unit'),
                 m('any hit, bench_trees\' unit')), 10)

row('ivm', 'IVM triangle test, scalar', 'Möller–Trumbore',
    '**0.80–0.86×** the time; equal in the 8-wide batch kernels ([intersection.md](docs/intersection.md))', 3,
    [Check('scalar float', '0.80–0.86', lambda c, r: job_intersection(c, r)['Scalar/Ivm']),
     Check('8-wide batch float', '1.0', lambda c, r: job_intersection(c, r)['Batch/Ivm'], '%.2f')],
    lambda m: '**%s×** the time; %s× in the 8-wide batch kernels ([intersection.md](docs/intersection.md))' % (
        m('scalar float'), m('8-wide batch float')), 2)


def layout_saving(c, r):
    mem = job_memory(c, r)
    return rng(v for (s, t, k), v in mem.items() if t == 'kd' and k == 31)


row('layout', 'compact subtree layout, kd-tree node bytes (K = 31)', 'Havran\'s subtree layout',
    '**81% smaller** (Szécsi 2009, Fig. 4.6: 47%) ([trees.md](docs/trees.md))', 1,
    [Check('saving, range over scenes', '81', layout_saving, '%.0f', '%')],
    lambda m: '**%s%% smaller** (Szécsi 2009, Fig. 4.6: 47%%) ([trees.md](docs/trees.md))' % m(
        'saving, range over scenes'), 0.2)


def eff(scene, method, base, sampler='random', extra=()):
    return lambda c, r: efficiency_ratio(conv(c, r, scene, sampler, extra)[method],
                                         conv(c, r, scene, sampler, extra)[base])


row('roulette', 'throughput roulette (default)', 'the classic roulette (Szécsi 2009, §2.1)',
    '**2.0×** efficiency on the Cornell box ([tracer.md](docs/tracer.md))', 3,
    [Check('cornell, throughput vs classic', '2.0', eff('cornell', 'throughput', 'classic'), '%.1f')],
    lambda m: '**%s×** efficiency on the Cornell box ([tracer.md](docs/tracer.md))' % m(
        'cornell, throughput vs classic'), 3)


def spectral_vs_throughput(c, r):
    vals = []
    for scene, extra in (('cornell', ()), ('cornell-glossy', ('--compare', 'roulette')), ('furnace', ())):
        d = conv(c, r, scene, 'random', extra)
        vals += [efficiency_ratio(d[m], d['throughput']) for m in ('spectral', 'throughput+spectral')]
    return rng(vals)


row('spectral', 'spectral roulette (Szécsi 2009, §2.2)', 'classic / throughput roulette',
    '**1.26–1.36** on the furnace (PCG), above 1.3 on Halton walks / **0.23–0.82**: does not survive the field\'s '
    'baseline ([claims.md](docs/claims.md))', 3,
    [Check('furnace, PCG, vs classic', '1.26–1.36', eff('furnace', 'spectral', 'classic')),
     Check('furnace, Halton walks, vs classic', '1.3', eff('furnace', 'spectral', 'classic', 'halton')),
     Check('vs throughput (spectral, throughput+spectral; 3 scenes)', '0.23–0.82', spectral_vs_throughput)],
    lambda m: '**%s** on the furnace (PCG), %s on Halton walks / **%s**: does not survive the field\'s baseline '
              '([claims.md](docs/claims.md))' % (m('furnace, PCG, vs classic'),
                                                 m('furnace, Halton walks, vs classic'),
                                                 m('vs throughput (spectral, throughput+spectral; 3 scenes)')), 4)

row('estimate', 'radiance-estimate roulette (Szécsi 2009, §2.3)', 'classic / throughput roulette',
    '1.04–1.26 on the Cornell box / 1.005 and 0.97: within the noise '
    '([claims.md](docs/claims.md), [tracer.md](docs/tracer.md))', 3,
    [Check('cornell, estimate vs classic', '1.04–1.26', eff('cornell', 'estimate', 'classic')),
     Check('cornell, throughput+estimate vs throughput', '1.005', eff('cornell', 'throughput+estimate', 'throughput'),
           '%.3f'),
     Check('cornell-glossy, throughput+estimate vs throughput', '0.97',
           eff('cornell-glossy', 'throughput+estimate', 'throughput', 'random', ('--compare', 'roulette')))],
    lambda m: '%s on the Cornell box / %s and %s (cornell, cornell-glossy) ([claims.md](docs/claims.md), '
              '[tracer.md](docs/tracer.md))' % (m('cornell, estimate vs classic'),
                                               m('cornell, throughput+estimate vs throughput'),
                                               m('cornell-glossy, throughput+estimate vs throughput')), 1)


def area(c, r):
    return conv(c, r, 'arealight')


row('correlated', 'correlated direct lighting, combined (Szécsi 2009, §3.2)', 'light importance sampling',
    'lowest RMSE at every spp, +0.2–7.1% time ([claims.md](docs/claims.md))', 3,
    [Check('spp levels where combined is not lowest', '0',
           lambda c, r: (lambda l, n: n - l)(*combined_lowest(area(c, r), ['importance', 'correlated'])), '%.0f'),
     Check('time over importance', '0.2–7.1', lambda c, r: time_overhead(area(c, r), 'combined', 'importance'),
           '%+.1f', '%')],
    lambda m: '%s; %s%% time ([claims.md](docs/claims.md))' % (
        'lowest RMSE at every spp in every run' if m.max('spp levels where combined is not lowest') == 0 else
        'not lowest at %s spp levels' % m('spp levels where combined is not lowest'),
        m('time over importance')), 2)


def lam(c, r, scene):
    return job_lambda(c, r, scene)


def lam_get(c, r, f):
    return [f(lam(c, r, s)) for s in ('arealight', 'cornell')]


def pen(d, lam_name, radius):
    for (region, l, rad), v in d.items():
        if region == 'penumbra' and rad == str(radius) and l.startswith(lam_name):
            return v
    raise ParseError('no penumbra row for lambda %s radius %s' % (lam_name, radius))


row('lambda', 'λ pooled over 3 × 3 pixels (Szécsi 2009, §3.1.1), statistical λ', 'per-pixel λ; λ = fractional visibility',
    '13–16% less variance, and the per-pixel λ\'s bias (1% of MSE) falls to 0.01–0.04%; 16–17% lower MSE than '
    'fractional visibility ([tracer.md](docs/tracer.md#λ-filtering-szécsi-2009-311))', 1,
    [Check('less variance, radius 1 vs 0 (arealight, cornell)', '13–16',
           lambda c, r: rng(lam_get(c, r, lambda d: 100 * (1 - pen(d, 'stat', 1)['variance'] /
                                                            pen(d, 'stat', 0)['variance']))), '%.0f', '%'),
     Check('bias²/MSE, radius 0', '1', lambda c, r: rng(lam_get(c, r, lambda d: 100 * pen(d, 'stat', 0)['bias2_share'])),
           '%.1f', '%'),
     Check('bias²/MSE, radius 1', '0.01–0.04',
           lambda c, r: rng(lam_get(c, r, lambda d: 100 * pen(d, 'stat', 1)['bias2_share'])), '%.2f', '%'),
     Check('lower MSE than visibility λ, radius 1', '16–17',
           lambda c, r: rng(lam_get(c, r, lambda d: 100 * (1 - pen(d, 'stat', 1)['mse'] / pen(d, 'vis', 1)['mse']))),
           '%.0f', '%')],
    lambda m: '%s%% less variance, and the per-pixel λ\'s bias (%s%% of MSE) falls to %s%%; %s%% lower MSE than '
              'fractional visibility ([tracer.md](docs/tracer.md#λ-filtering-szécsi-2009-311))' % (
                  m('less variance, radius 1 vs 0 (arealight, cornell)'), m('bias²/MSE, radius 0'),
                  m('bias²/MSE, radius 1'), m('lower MSE than visibility λ, radius 1')), 6)


def env(c, r):
    return job_envmap(c, r)


row('envmap', 'correlated environment lighting, combined (Szécsi 2009, §3.3)', 'map importance sampling + MIS',
    'lowest RMSE at every spp with 16 samples per vertex (not with 4), +1–8% time over correlated, 5.2–5.3x MIS\'s '
    'efficiency ([claims.md](docs/claims.md#envmap-correlated-environment-lighting-szécsi-2009-33))', 3,
    [Check('spp levels where combined is not lowest (K = 16)', '0',
           lambda c, r: (lambda l, n: n - l)(*combined_lowest(env(c, r), ['importance', 'importance-k', 'correlated',
                                                                         'combined-3.5'])), '%.0f'),
     Check('time over correlated', '1–8', lambda c, r: time_overhead(env(c, r), 'combined', 'correlated'), '%+.0f',
           '%'),
     Check('efficiency vs MIS', '5.2–5.3', lambda c, r: efficiency_ratio(env(c, r)['combined'],
                                                                         env(c, r)['importance']), '%.1f', 'x')],
    lambda m: '%s with 16 samples per vertex (not with 4: not re-measured), %s%% time over correlated, %sx MIS\'s '
              'efficiency ([claims.md](docs/claims.md#envmap-correlated-environment-lighting-szécsi-2009-33))' % (
                  'lowest RMSE at every spp' if m.max('spp levels where combined is not lowest (K = 16)') == 0 else
                  'not lowest RMSE at %s spp levels' % m('spp levels where combined is not lowest (K = 16)'),
                  m('time over correlated'), m('efficiency vs MIS')), 1)


def halton_time(c, r):
    """Equal-error time halton / PCG at the largest spp, default roulette: the MSE ratio of the
    two runs (same seed) times the ratio of their processes' CPU time (every method, the same
    work but the sampler; bench_convergence's own seconds are wall time, which the shared
    machine inflates by 2-3x, unevenly between runs). Both runs read the cached reference."""
    h, p = conv(c, r, 'cornell', 'halton')['throughput'][-1], conv(c, r, 'cornell')['throughput'][-1]
    cpu = [c.cpu.get(('bench_convergence_cornell_%s' % s, r)) for s in ('halton', 'random')]
    if None in cpu:
        raise ParseError('no CPU time for the cornell runs (logs of an older results.py: rerun without --resume)')
    return (h[2] / p[2]) ** 2 * cpu[0] / cpu[1]


row('halton', 'Halton sampler in the path tracer', 'PCG',
    '0.87× the equal-error time at 64 spp ([sampling.md](docs/sampling.md))', 3,
    [Check('cornell, 64 spp, MSE·time halton / PCG', '0.87', halton_time)],
    lambda m: '%s× the equal-error time at 64 spp (MSE ratio × CPU-time ratio) '
              '([sampling.md](docs/sampling.md))' % m('cornell, 64 spp, MSE·time halton / PCG'), 3)


def occ(scene, spheres, i):
    def get(c, r):
        d = job_occluders(c, r)
        if scene not in d:
            raise Skip('bench_occluders rendered no %s (mesh missing or --quick)' % scene)
        if spheres not in d[scene]:
            raise ParseError('no %d-sphere row for %s' % (spheres, scene))
        return d[scene][spheres][i]
    return get


row('occluders', 'occluder spheres for VPL visibility (Szécsi 2009, ch. 5)',
    'shadow rays through the wide BVH (through a kd-tree)',
    '5.2× (14.5×) at relative RMSE 0.039 on the torus knot, 2.7× (5.6×) at 0.05 on the bunny '
    '([occluders.md](docs/occluders.md))', 3,
    [Check('torus knot, 10 spheres, speedup', '5.2', occ('torus-knot', 10, 0), '%.1f', '×'),
     Check('torus knot, 10 spheres, rel. RMSE', '0.039', occ('torus-knot', 10, 1), '%.3f'),
     Check('bunny, 100 spheres, speedup', '2.7', occ('bunny', 100, 0), '%.1f', '×'),
     Check('bunny, 100 spheres, rel. RMSE', '0.05', occ('bunny', 100, 1), '%.3f')],
    lambda m: '%s× at relative RMSE %s on the torus knot (10 spheres), %s× at %s on the bunny (100 spheres); '
              'through the kd-tree not re-measured (bench_occluders times the wide BVH only; an earlier run: '
              '14.5× and 5.6×) ([occluders.md](docs/occluders.md))' % (
                  m('torus knot, 10 spheres, speedup'), m('torus knot, 10 spheres, rel. RMSE'),
                  m('bunny, 100 spheres, speedup'), m('bunny, 100 spheres, rel. RMSE')), 4)


def cone(count, what):
    def get(c, r):
        d = job_cones(c, r)
        n = min(d, key=lambda k: abs(k - count))
        if abs(n - count) > 0.2 * count:
            raise Skip('bench_cones measured no count near %d' % count)
        return d[n][what]
    return get


row('cones', 'ray-tile hierarchy over refracted rays (Szécsi 2009, ch. 6)', 'brute force; the wide BVH',
    '2.1–3.4× brute force at 100 triangles (Szécsi 2009: 2×), 8–16× at 5k with fixed 16 × 16 tiles, 15–24× with adaptive '
    'tiles (Szécsi 2009: 15–20×); the wide BVH is faster still, 5–173× the tiles ([cones.md](docs/cones.md))', 3,
    [Check('100 triangles, fixed tiles vs brute', '2.1–3.4', cone(100, 'tiles'), '%.1f', '×'),
     Check('5k triangles, fixed tiles vs brute', '8–16', cone(5000, 'tiles'), '%.1f', '×'),
     Check('5k triangles, adaptive tiles vs brute', '15–24', cone(5000, 'tiles_split'), '%.1f', '×'),
     Check('wide BVH vs fixed tiles, 100-50k triangles', '5–173',
           lambda c, r: rng(v['tree_vs_tiles'] for v in job_cones(c, r).values()), '%.0f', '×')],
    lambda m: '%s× brute force at 100 triangles (Szécsi 2009: 2×), %s× at 5k with fixed 16 × 16 tiles, %s× with '
              'adaptive tiles (Szécsi 2009: 15–20×); the wide BVH is faster still, %s× the tiles '
              '([cones.md](docs/cones.md))' % (
                  m('100 triangles, fixed tiles vs brute'), m('5k triangles, fixed tiles vs brute'),
                  m('5k triangles, adaptive tiles vs brute'), m('wide BVH vs fixed tiles, 100-50k triangles')), 4)


def lights_speedup(scene, family):
    """The standard ray tracer's time over the fastest `family` row (cuts, sparse-recon: any threshold or agreement) at
    E <= 2% (--quick: at any E, the sizes are too small to converge)."""
    def get(c, r):
        d = job_lights(c, r).get(scene) or {}
        if 'standard' not in d:
            raise ParseError('no standard row for %s' % scene)
        limit = 1.0 if c.a.quick else 0.02
        ranged = family in ('cuts', 'sparse-recon')  # one row per threshold or agreement
        ok = [v[0]['seconds'] for m, v in d.items() if (m == family or (ranged and m.startswith(family + '-'))) and
              not m.endswith('-build') and v[0]['error_E'] <= limit]
        if not ok:
            raise ParseError('no %s row at E <= %g on %s' % (family, limit, scene))
        return d['standard'][0]['seconds'] / min(ok)
    return get


def lights_tree_vs_power(scene):
    """The path tracer's MSE x time of the light tree over power selection (medians of time, mean MSE)."""
    def get(c, r):
        d = job_lights(c, r).get(scene) or {}
        if 'tree' not in d or 'power' not in d:
            raise ParseError('no tree and power rows for %s' % scene)
        cost = {m: statistics.mean(v['rmse'] ** 2 for v in d[m]) * statistics.median(v['seconds'] for v in d[m])
                for m in ('tree', 'power')}
        return cost['tree'] / cost['power']
    return get


LIGHTS_AGAINST = 'the standard ray tracer (a shadow ray per light, 8-wide BVH), direct light at primary hits'
row('lights-lie', 'local illumination environments (Fernandez 2004, ch. 3–4), with and without masking',
    LIGHTS_AGAINST,
    '**5.4× / 6.4×** (masking) at E ≤ 2% on the 100-light LIE hall (Fernandez 2004: 24.1× / 29.2×); 6.7× on the '
    '800-light hall (14.6×) ([lights.md](docs/lights.md#measured))', 3,
    [Check('lie-hall, LIE x standard at E<=2%', '5.4', lights_speedup('lie-hall', 'lie'), '%.1f', '×'),
     Check('lie-hall, LIE with masking x standard', '6.4', lights_speedup('lie-hall', 'lie-mask'), '%.1f', '×'),
     Check('hall, LIE x standard at E<=2%', '6.7', lights_speedup('hall', 'lie'), '%.1f', '×')],
    lambda m: '**%s× / %s×** (masking) at E ≤ 2%% on the 100-light LIE hall (Fernandez 2004: 24.1× / 29.2×); %s× on '
              'the 800-light hall (14.6×) ([lights.md](docs/lights.md#measured))' % (
                  m('lie-hall, LIE x standard at E<=2%'), m('lie-hall, LIE with masking x standard'),
                  m('hall, LIE x standard at E<=2%')), 6)
row('lights-cuts', 'light cluster trees, dense cuts (Fernandez 2004, §5.2)', LIGHTS_AGAINST,
    '**6.4×** at E ≤ 2% on the kitchen (4608 oriented lights; Fernandez 2004: 11.5×), **0.9×** on the hall (800 point '
    'and spot lights; 2.8–3.86×) ([lights.md](docs/lights.md#measured))', 3,
    [Check('kitchen, cuts x standard at E<=2%', '6.4', lights_speedup('kitchen', 'cuts'), '%.1f', '×'),
     Check('hall, cuts x standard at E<=2%', '0.9', lights_speedup('hall', 'cuts'), '%.1f', '×')],
    lambda m: '**%s×** at E ≤ 2%% on the kitchen (4608 oriented lights; Fernandez 2004: 11.5×), **%s×** on the hall '
              '(800 point and spot lights; 2.8–3.86×) ([lights.md](docs/lights.md#measured))' % (
                  m('kitchen, cuts x standard at E<=2%'), m('hall, cuts x standard at E<=2%')), 0)
row('lights-sparse', 'sparse sampling of cuts: reconstruction cuts (Fernandez 2004, §5.3)', LIGHTS_AGAINST,
    '**7.1×** at E ≤ 2% on the kitchen (Fernandez 2004: 51.1×), 0.9× on the LIE hall; interpolation not at E ≤ 2% '
    'at the seed\'s density ([lights.md](docs/lights.md#measured))', 3,
    [Check('kitchen, sparse reconstruction x standard at E<=2%', '7.1', lights_speedup('kitchen', 'sparse-recon'), '%.1f', '×'),
     Check('lie-hall, sparse reconstruction x standard at E<=2%', '0.9', lights_speedup('lie-hall', 'sparse-recon'), '%.1f', '×')],
    lambda m: '**%s×** at E ≤ 2%% on the kitchen (Fernandez 2004: 51.1×), %s× on the LIE hall; interpolation not at '
              'E ≤ 2%% at the seed\'s density ([lights.md](docs/lights.md#measured))' % (
                  m('kitchen, sparse reconstruction x standard at E<=2%'),
                  m('lie-hall, sparse reconstruction x standard at E<=2%')), 0)
row('lights-tree', 'stochastic light tree (Conty Estevez and Kulla 2018) in the path tracer, MSE·time at equal spp',
    'power light selection (Cycles 3.4\'s)',
    '**0.06×** on the 800-light hall, **1.0×** on the 72-light kitchen ([lights.md](docs/lights.md#measured))', 3,
    [Check('hall, tree / power MSE·time', '0.06', lights_tree_vs_power('hall'), '%.2f', '×'),
     Check('kitchen, tree / power MSE·time', '1.0', lights_tree_vs_power('kitchen'), '%.1f', '×')],
    lambda m: '**%s×** on the 800-light hall, **%s×** on the 72-light kitchen ([lights.md](docs/lights.md#measured))' % (
        m('hall, tree / power MSE·time'), m('kitchen, tree / power MSE·time')), 0)


def photons_knn(size, k):
    """glint's kNN speed over nanoflann's on the smallest or largest photon count bench_photons ran."""
    def get(c, r):
        d = job_photons(c, r)
        counts = sorted({p for p, kk in d if kk == k})
        if not counts:
            raise ParseError('no k = %d row in bench_photons' % k)
        ratio, same = d[(counts[0] if size == 'smallest' else counts[-1], k)]
        if not same:
            raise ParseError('glint and nanoflann found different neighbours (k = %d)' % k)
        return ratio
    return get


row('photons-knn', 'photon map k nearest neighbours: the left-balanced kd-tree (Jensen 2001; Larsen 2004, §4.3)',
    'nanoflann 1.4.2, the same photons and queries, one thread',
    '**1.46× / 2.85×** nanoflann\'s speed at k = 50 (10⁴ / 10⁶ photons), **6.2×** at k = 500 (10⁶); the same '
    'neighbours ([photons.md](docs/photons.md#bench_photons))', 1,
    [Check('k = 50, 10^4 photons', '1.46', photons_knn('smallest', 50), '%.2f', '×'),
     Check('k = 50, 10^6 photons', '2.85', photons_knn('largest', 50), '%.2f', '×'),
     Check('k = 500, 10^6 photons', '6.2', photons_knn('largest', 500), '%.1f', '×')],
    lambda m: '**%s× / %s×** nanoflann\'s speed at k = 50 (10⁴ / 10⁶ photons), **%s×** at k = 500 (10⁶); the same '
              'neighbours ([photons.md](docs/photons.md#bench_photons))' % (
                  m('k = 50, 10^4 photons'), m('k = 50, 10^6 photons'), m('k = 500, 10^6 photons')), 3)


def caustics_ratio(budget, method, against, key='rmse'):
    """RMSE of `method` over `against`'s at equal time `budget` on cornell-caustics."""
    def get(c, r):
        d = job_caustics(c, r)
        return d[(budget, method)][key] / d[(budget, against)][key]
    return get


row('caustics', 'caustics at equal time on the Cornell box with a glass sphere and a mirror cube: SPPM (Hachisuka and '
    'Jensen 2009), RMSE at 2 / 8 s, pixels away from the light',
    'glint\'s path tracer; Cycles 3.4 (Glass BSDF sharp, caustics on), same scene exported',
    '**0.55 / 0.58** of glint path\'s RMSE, **0.29 / 0.40** of Cycles\'; over the whole image 0.66 / 1.00 of Cycles\', '
    '1.3 / 1.4 of glint path\'s ([photons.md](docs/photons.md#caustics-at-equal-time))', 1,
    [Check('2 s, sppm / glint path', '0.55', caustics_ratio(2.0, 'glint sppm', 'glint path')),
     Check('8 s, sppm / glint path', '0.58', caustics_ratio(8.0, 'glint sppm', 'glint path')),
     Check('2 s, sppm / Cycles', '0.29', caustics_ratio(2.0, 'glint sppm', 'Cycles 3.4 path')),
     Check('8 s, sppm / Cycles', '0.40', caustics_ratio(8.0, 'glint sppm', 'Cycles 3.4 path')),
     Check('2 s, image, sppm / Cycles', '0.66', caustics_ratio(2.0, 'glint sppm', 'Cycles 3.4 path', 'rmse_image')),
     Check('8 s, image, sppm / Cycles', '1.00', caustics_ratio(8.0, 'glint sppm', 'Cycles 3.4 path', 'rmse_image')),
     Check('2 s, image, sppm / glint path', '1.3', caustics_ratio(2.0, 'glint sppm', 'glint path', 'rmse_image'), '%.1f'),
     Check('8 s, image, sppm / glint path', '1.4', caustics_ratio(8.0, 'glint sppm', 'glint path', 'rmse_image'), '%.1f')],
    lambda m: '**%s / %s** of glint path\'s RMSE, **%s / %s** of Cycles\'; over the whole image %s / %s of Cycles\', '
              '%s / %s of glint path\'s ([photons.md](docs/photons.md#caustics-at-equal-time))' % (
                  m('2 s, sppm / glint path'), m('8 s, sppm / glint path'), m('2 s, sppm / Cycles'), m('8 s, sppm / Cycles'),
                  m('2 s, image, sppm / Cycles'), m('8 s, image, sppm / Cycles'), m('2 s, image, sppm / glint path'),
                  m('8 s, image, sppm / glint path')), 10)


# The rows README marked stale run first, the slowest per value (lambda, Cycles) last.
RUN_FIRST = ['cones', 'occluders', 'trees', 'ivm', 'layout', 'roulette', 'estimate', 'halton', 'spectral',
             'correlated', 'envmap', 'lambda']


# --------------------------------------------------------------------------- measure

def stated_values(check):
    """README's number(s) as floats: '2.0' -> (2.0,), '1.06–1.99' -> (1.06, 1.99)."""
    return tuple(float(x) for x in str(check.stated).replace('+', '').split('–'))


def stated_str(check):
    return str(check.stated)


def half_unit(text):
    """Half a unit of the last digit the stated number shows ('2.0' -> 0.05, '1.005' -> 0.0005, '81' -> 0.5)."""
    text = text.strip().lstrip('+')
    return 0.5 * 10 ** (-len(text.split('.')[1])) if '.' in text else 0.5


class Measured:
    """The values of one row's checks over the repetitions; formats them for the table."""

    def __init__(self, rowdef, values, reps_done):
        self.row, self.values, self.reps = rowdef, values, reps_done

    def _check(self, label):
        return next(c for c in self.row['checks'] if c.label == label)

    def ends(self, label):
        """Per repetition (lo, hi)."""
        return [v if isinstance(v, tuple) else (v, v) for v in self.values[label]]

    def median(self, label):
        e = self.ends(label)
        return statistics.median(x[0] for x in e), statistics.median(x[1] for x in e)

    def max(self, label):
        return max(x[1] for x in self.ends(label))

    def __call__(self, label):
        c = self._check(label)
        lo, hi = self.median(label)
        f = lambda v: c.fmt % v
        return f(lo) if f(lo) == f(hi) else f(lo) + '–' + f(hi).lstrip('+')

    def spread(self, label):
        c = self._check(label)
        e = self.ends(label)
        lo, hi = [x[0] for x in e], [x[1] for x in e]
        if len(e) == 1:
            return 'one run'
        if lo == hi:
            return (c.fmt % min(lo)) + '…' + (c.fmt % max(lo)).lstrip('+')
        return 'low end %s…%s, high end %s…%s' % (c.fmt % min(lo), c.fmt % max(lo), c.fmt % min(hi),
                                                   c.fmt % max(hi))

    def spread_note(self):
        return 'medians of %d runs' % self.reps if self.reps > 1 else 'one run'

    def flag(self, label):
        """'' when the stated value lies inside the measured spread (widened by the stated
        number's rounding), else 'OUTSIDE'."""
        c = self._check(label)
        e = self.ends(label)
        texts = str(c.stated).split('–')
        if len(texts) == 1:
            texts = texts * 2
        bad = False
        for k, text in enumerate(texts):
            st = float(text.replace('+', ''))
            vals = [x[k] for x in e]
            tol = half_unit(text)
            if st < min(vals) - tol or st > max(vals) + tol:
                bad = True
        return 'OUTSIDE' if bad else ''


def measure_row(c, r):
    """Returns (Measured or None, why not)."""
    values = {ch.label: [] for ch in r['checks']}
    reps = 1 if c.a.quick else (c.a.reps if c.a.reps and r['reps'] > 1 else r['reps'])
    for rep in range(reps):
        for ch in r['checks']:
            values[ch.label].append(ch.get(c, rep))
    return Measured(r, values, reps)


def table_line(cells):
    return '| ' + ' | '.join(cells) + ' |'


def default_scenes():
    """../shared/scenes beside the repository (or beside a worktree's parent folder)."""
    for up in (('..',), ('..', '..')):
        p = os.path.join(ROOT, *up, 'shared', 'scenes')
        if os.path.isdir(p):
            return os.path.normpath(p)
    return os.path.join(ROOT, '..', 'shared', 'scenes')


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument('--quick', action='store_true', help='smoke run: tiny sizes, one repetition, rewrites nothing')
    p.add_argument('--rows', help='comma-separated row keys (see --list); the others keep README\'s text')
    p.add_argument('--skip', help='comma-separated row keys not to run')
    p.add_argument('--skip-why', help='the reason the table gives for the --skip rows')
    p.add_argument('--list', action='store_true')
    p.add_argument('--resume', action='store_true',
                   help='reuse the logs of benchmark runs that finished with the same command (an interrupted run)')
    p.add_argument('--reps', type=int, default=0, help='repetitions of every timed row (default: the row\'s, 3)')
    p.add_argument('--core', type=int, default=1, help='the core every benchmark is pinned to (taskset -c)')
    p.add_argument('--build-dir', default=os.path.join(ROOT, 'build'))
    p.add_argument('--scenes', default=os.environ.get('GLINT_SCENES', default_scenes()),
                   help='folder of the OBJ meshes (bunny, diplodocus, turbine, cornell_box); default ../shared/scenes')
    p.add_argument('--tree-rays', type=int, default=1000000, help='rays per set in the Embree comparison')
    p.add_argument('--readme', default=os.path.join(ROOT, 'README.md'))
    p.add_argument('--doc', default=os.path.join(ROOT, 'docs', 'results.md'))
    a = p.parse_args()
    a.build_dir = os.path.abspath(a.build_dir)

    if a.list:
        for r in ROWS:
            print('%-15s ~%4.1f min  %s' % (r['key'], r['minutes'], r['what']))
        return 0
    keys = [r['key'] for r in ROWS]
    chosen = a.rows.split(',') if a.rows else list(keys)
    for k in chosen + (a.skip.split(',') if a.skip else []):
        if k not in keys:
            p.error('unknown row %r (rows: %s)' % (k, ', '.join(keys)))
    skipped = set(a.skip.split(',')) if a.skip else set()
    full = not a.quick and not a.rows  # --skip still writes: skipped rows are marked 'not re-measured'
    c = Ctx(a)
    if not os.path.isdir(a.scenes):
        print('results: no meshes at %s (--scenes): rows that need them say so' % a.scenes)
    t_start = time.time()

    out = io.StringIO()

    def say(s=''):
        print(s, flush=True)
        out.write(s + '\n')

    results, failed = {}, []
    for r in sorted(ROWS, key=lambda r: RUN_FIRST.index(r['key']) if r['key'] in RUN_FIRST else len(RUN_FIRST)):
        if r['key'] not in chosen:
            continue
        if r['key'] in skipped:
            results[r['key']] = (None, a.skip_why or 'left out of this run (--skip; the row takes about %.0f minutes)' % (
                r['minutes']))
            continue
        t0 = time.time()
        try:
            results[r['key']] = (measure_row(c, r), '')
        except Skip as e:
            results[r['key']] = (None, str(e))
        except (ParseError, RuntimeError, KeyError, ValueError, ZeroDivisionError) as e:
            results[r['key']] = (None, '%s: %s' % (type(e).__name__, e))
            failed.append(r['key'])
        print('results: row %s done in %.0f s%s' % (r['key'], time.time() - t0,
                                                     '' if results[r['key']][0] else ': ' + results[r['key']][1]),
              flush=True)

    elapsed = time.time() - t_start
    git = subprocess.run(['git', '-C', ROOT, 'rev-parse', '--short', 'HEAD'], stdout=subprocess.PIPE,
                         stderr=subprocess.DEVNULL, text=True).stdout.strip()
    dirty = subprocess.run(['git', '-C', ROOT, 'status', '--porcelain', '--untracked-files=no'],
                           stdout=subprocess.PIPE, text=True).stdout.strip()
    cpu = ''
    try:
        cpu = next(l.split(':', 1)[1].strip() for l in open('/proc/cpuinfo') if l.startswith('model name'))
    except (OSError, StopIteration):
        pass
    load = os.getloadavg() if hasattr(os, 'getloadavg') else (0, 0, 0)
    mode = 'quick (smoke run: tiny sizes, numbers meaningless)' if a.quick else (
        'full' if full else 'partial (--rows)')
    say('# Results: README\'s table re-measured')
    say()
    say('Written by `bash tools/results.sh%s` (%s run); do not edit by hand.' % (
        ' --skip ' + a.skip if a.skip else '', mode.split(' ')[0]))
    say()
    say('- commit %s%s; %s; %d cores; load average at the end %.1f / %.1f / %.1f' % (
        git, ' (with local changes)' if dirty else '', cpu, os.cpu_count() or 0, *load))
    say('- %s UTC; benchmarks %.1f minutes (the sum of the runs below%s), this invocation %.1f minutes; every '
        'benchmark single-threaded, `taskset -c %d`' % (
            time.strftime('%Y-%m-%d %H:%M', time.gmtime()), sum(c.times.values()) / 60,
            '; %d of them read from an earlier invocation\'s logs with --resume' % len(c.reused) if c.reused else '',
            elapsed / 60, a.core))
    say('- binaries from `%s`; logs (every benchmark\'s full output, its command line first) in `%s`' % (
        a.build_dir, c.logs))
    say('- a check is flagged OUTSIDE when README\'s number lies outside the measured run-to-run spread (min–max over '
        'the repetitions) widened by the stated number\'s rounding')
    say()
    say('## Checks: stated against measured')
    say()
    say(table_line(['row', 'check', 'README states', 'measured (median)', 'spread over runs', 'runs', 'flag']))
    say('|---|---|---|---|---|---|---|')
    for r in ROWS:
        if r['key'] not in results:
            continue
        m, why = results[r['key']]
        if m is None:
            say(table_line([r['key'], '—', '—', 'not re-measured: ' + why, '', '', '']))
            continue
        for ch in r['checks']:
            say(table_line([r['key'], ch.label, stated_str(ch) + ch.unit, m(ch.label) + ch.unit, m.spread(ch.label),
                            str(m.reps), m.flag(ch.label)]))
    say()
    say('## The table README includes')
    say()
    lines = [table_line(['what', 'against', 'result']), '|---|---|---|']
    for r in ROWS:
        res = results.get(r['key'])
        if res and res[0] is not None:
            cell = r['cell'](res[0])
        else:
            why = res[1] if res else 'not in this run (--rows)'
            cell = r['stated_cell'] + ' — *not re-measured: %s*' % why
        lines.append(table_line([r['what'], r['against'], cell]))
    for l in lines:
        say(l)
    say()
    say('## Commands and times')
    say()
    say('| benchmark | repetition | wall seconds | CPU seconds | log |')
    say('|---|---|---|---|---|')
    for (name, rep), t in sorted(c.times.items()):
        cpu = c.cpu.get((name, rep))
        say('| %s | %d | %.1f | %s | %s.%d.log |' % (name, rep, t, '%.1f' % cpu if cpu is not None else '—', name, rep))

    bad = failed  # rows whose benchmark failed or whose output did not parse (a Skip says why it could not run)
    if a.quick:
        path = os.path.join(c.work, 'quick.md')
        with open(path, 'w') as f:
            f.write(out.getvalue())
        print('results: --quick: wrote %s (README and docs untouched); %.1f s' % (path, elapsed))
        if bad:
            print('results: --quick FAILED: rows that did not run or parse: ' + ', '.join(bad), file=sys.stderr)
            return 1
        return 0
    if not full:
        path = os.path.join(c.work, 'partial.md')
        with open(path, 'w') as f:
            f.write(out.getvalue())
        print('results: partial run: wrote %s (README and docs/results.md only from a full run)' % path)
        return 0
    with open(a.doc, 'w') as f:  # README's links are relative to the root, the doc's to docs/
        f.write(out.getvalue().replace('](docs/', ']('))
    text = open(a.readme).read()
    if BEGIN in text and END in text:
        head, rest = text.split(BEGIN, 1)
        _, tail = rest.split(END, 1)
        with open(a.readme, 'w') as f:
            f.write(head + BEGIN + '\n' + '\n'.join(lines) + '\n' + END + tail)
        print('results: wrote %s and the table in %s' % (a.doc, a.readme))
    else:
        print('results: wrote %s; %s has no %s ... %s markers: table not written' % (a.doc, a.readme, BEGIN, END))
    return 0


if __name__ == '__main__':
    sys.exit(main())
