#!/usr/bin/env python3
"""A build without -march flags against the -march=native build, mesh by mesh, interleaved.

For every mesh of --scenes, --reps times: bench_user_meshes (native) and
bench_user_meshes_portable (no -march flags: the run-time kernels of core/isa.hpp) on that mesh
alone, in alternating order,
each through MeshBvh's public calls against Embree HIGH in the same process. A run's glint
throughput is divided by Embree's in that run (the same Embree library in both binaries: it
takes out the machine's drift between runs); the printed ratio is portable over native, the
median over the repetitions, per query (incoherent and primary closest hit, any hit) and the
geometric mean over the meshes.

    python3 tools/portable_native.py --build build --scenes ../shared/scenes --reps 3 --core 1

bench_user_meshes holds only the user's tree type in its translation unit, as a renderer's
would; bench_trees (--user-meshes, added for binaries named bench_trees*) runs the same rows
from a unit with dozens of tree types. Other binaries and arguments: e.g. the AVX2 kernels
against a native build without AVX-512 (configured with CMAKE_CXX_FLAGS=-mno-avx512f):

    python3 tools/portable_native.py --native build-avx2/benchmarks/bench_user_meshes --portable-args='--isa avx2'
"""
import argparse
import csv
import math
import os
import statistics
import subprocess
import sys
import tempfile

QUERIES = ('incoherent', 'primary', 'shadow')


def run(binary, extra, stem, a, out):
    mode = ['--user-meshes'] if os.path.basename(binary).startswith('bench_trees') else []
    cmd = ['taskset', '-c', str(a.core), binary] + extra + mode + ['--scenes', a.scenes, '--only', stem,
           '--no-generated', '--reps', str(a.passes), '--builds', '1', '--csv', out]  # builds are not compared
    if a.cpu_time:
        cmd.append('--cpu-time')
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if p.returncode != 0:
        sys.exit('portable_native: %s failed:\n%s' % (' '.join(cmd), p.stdout))
    ratios = {}
    with open(out) as f:
        for r in csv.DictReader(f):
            if r['embree_quality'].lower() == 'high' and r['rays'] in QUERIES:
                ratios[r['rays']] = float(r['mrays_per_s']) / float(r['embree_mrays_per_s'])
    if set(ratios) != set(QUERIES):
        sys.exit('portable_native: %s gave rows for %s, not %s' % (binary, sorted(ratios), QUERIES))
    return ratios


def main():
    p = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    p.add_argument('--build', default='build', help='build folder with benchmarks/bench_user_meshes and bench_user_meshes_portable')
    p.add_argument('--scenes', default=os.path.join(os.path.dirname(__file__), '..', '..', 'shared', 'scenes'))
    p.add_argument('--reps', type=int, default=3, help='alternating runs of each binary per mesh')
    p.add_argument('--passes', type=int, default=3, help="the program's own alternating passes per run")
    p.add_argument('--core', type=int, default=1, help='taskset core')
    p.add_argument('--cpu-time', action='store_true',
                   help="time passes by the thread's CPU clock (both binaries): other processes on the core not counted")
    p.add_argument('--native', help='the native binary (default: BUILD/benchmarks/bench_user_meshes)')
    p.add_argument('--portable', help='the portable binary (default: BUILD/benchmarks/bench_user_meshes_portable)')
    p.add_argument('--native-args', default='', help="extra arguments of the native binary, e.g. '--isa avx2'")
    p.add_argument('--portable-args', default='', help="extra arguments of the portable binary, e.g. '--isa avx2'")
    a = p.parse_args()
    native = a.native or os.path.join(a.build, 'benchmarks', 'bench_user_meshes')
    portable = a.portable or os.path.join(a.build, 'benchmarks', 'bench_user_meshes_portable')
    # By role, not by path: the same binary may run both sides with different arguments.
    runs = {'native': (native, a.native_args.split()), 'portable': (portable, a.portable_args.split())}
    for b in (native, portable):
        if not os.access(b, os.X_OK):
            sys.exit('portable_native: %s not built (cmake --build %s --target bench_user_meshes bench_user_meshes_portable)' % (b, a.build))
    stems = sorted(f[:-4] for f in os.listdir(a.scenes) if f.endswith('.obj'))
    if not stems:
        sys.exit('portable_native: no .obj in ' + a.scenes)
    print('%-16s %s' % ('mesh', '  '.join('%-24s' % ('%s portable/native' % q) for q in QUERIES)))
    per_query = {q: [] for q in QUERIES}
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, 'rows.csv')
        for stem in stems:
            ratios = {q: [] for q in QUERIES}
            for rep in range(a.reps):
                order = ('native', 'portable') if rep % 2 == 0 else ('portable', 'native')
                got = {role: run(*runs[role], stem, a, out) for role in order}
                for q in QUERIES:
                    ratios[q].append(got['portable'][q] / got['native'][q])
            cells = []
            for q in QUERIES:
                m = statistics.median(ratios[q])
                per_query[q].append(m)
                cells.append('%-24s' % ('%.3f (%.3f-%.3f)' % (m, min(ratios[q]), max(ratios[q]))))
            print('%-16s %s' % (stem, '  '.join(cells)), flush=True)
    print('%-16s %s' % ('geometric mean', '  '.join(
        '%-24s' % ('%.3f' % math.exp(statistics.mean(math.log(x) for x in per_query[q]))) for q in QUERIES)))
    return 0


if __name__ == '__main__':
    sys.exit(main())
