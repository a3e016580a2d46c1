#!/usr/bin/env python3
"""Caustics at equal time: glint's photon integrators against its path tracer and Cycles 3.4.

    python3 tools/caustics_table.py                      # cornell-caustics, 64^2, budgets 2,8 s
    python3 tools/caustics_table.py --quick              # a smoke run
    python3 tools/caustics_table.py --scene cornell-caustics-point --budgets 4

One command prints the table: for each time budget, the RMSE of glint-render's path tracer
(--integrator path --spp 1 --time-budget T: passes of 1 spp), SPPM (--integrator sppm
--time-budget T) and the photon map (--integrator photons --time-budget T: passes of new maps),
and of Cycles 3.4 (its time limit T, the same scene exported by tools/peer_cycles.py: Glass BSDF
sharp, caustics on), every render on one thread pinned to --core.

Errors: each renderer against its own long path-traced reference, rendered as two halves of
--ref-spp / 2 spp (glint's path tracer; Cycles), as tools/peer_cycles.py measures its rows
(or, with --reference sppm, the default for scenes lit by a point light, whose caustics no path
tracer samples: every renderer against two halves of --ref-seconds of glint's SPPM):
RMSE = sqrt(MSE - mean((A - B)^2) / 4), the reference's own noise taken out; over the pixels
away from the area light ("no light": its edge pixels' coverage error would swamp the rest) and
over the whole image. glint's photon
integrators are measured against glint's path-traced reference. Times: CPU seconds of the
glint-render process (user + system: scene set-up, tree build, maps and render) and Cycles'
process time around its render call (sync, BVH build and render), as peer_cycles.py does;
a budget bounds the passes, so a renderer may spend a little more than T (the table prints
what each spent). The machine is shared: the renderers alternate at each budget.
"""
import argparse
import json
import math
import os
import shutil
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import peer_cycles as pc  # noqa: E402

GLINT_METHODS = {
    'path': ['--integrator', 'path', '--spp', '1'],
    'sppm': ['--integrator', 'sppm', '--photons', '{photons}', '--radius', '{radius}', '--camera-samples', '{camera}'],
    'photons': ['--integrator', 'photons', '--photons', '{pm_photons}', '--radius', '{radius}', '--knn', '{knn}',
                '--final-gather', '{gather}', '--spp', '4'],
}


def rmse(img, ref, mask=None):
    return math.sqrt(max(pc.mse(img, ref, mask), 0.0))


def light_mask(scene_json, size):
    """Pixels away from the area lights: everything but the bounding box of the emissive
    triangles' projections (glint's camera), grown by one pixel. The light's edge pixels hold
    emission (17 in red) times the pixel's coverage, an antialiasing error that would swamp
    light transport's; the point-light scene keeps every pixel."""
    np = pc.np
    keep = np.ones((size, size), bool)
    cam = scene_json['camera']
    eye, wv, u, v, _ = pc.glint_camera_dirs(cam, size, size, np.zeros(1), np.zeros(1))
    t = math.tan(cam['fov_y'] * 0.5)
    tris = np.array(scene_json['triangles'], float).reshape(-1, 3, 3)
    emissive = np.array([max(m['emission']) > 0 for m in scene_json['materials']])[np.array(scene_json['material_of'])]
    if not emissive.any():
        return keep
    pts = tris[emissive].reshape(-1, 3) - eye
    z = pts @ wv
    sx = ((pts @ u) / z / t + 1) / 2 * size  # glint: d = w + u (2 sx - 1) t aspect + v (1 - 2 sy) t
    sy = (1 - (pts @ v) / z / t) / 2 * size
    x0, x1 = int(max(math.floor(sx.min()) - 1, 0)), int(min(math.ceil(sx.max()) + 1, size))
    y0, y1 = int(max(math.floor(sy.min()) - 1, 0)), int(min(math.ceil(sy.max()) + 1, size))
    keep[y0:y1, x0:x1] = False
    return keep


def main():
    p = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    p.add_argument('--scene', default='cornell-caustics')
    p.add_argument('--size', type=int, default=64)
    p.add_argument('--budgets', default='2,8', help='time budgets, seconds')
    p.add_argument('--ref-spp', type=int, default=8192, help='reference spp (two halves)')
    p.add_argument('--photons', type=int, default=50000)
    p.add_argument('--radius', type=float, default=0.05)
    p.add_argument('--knn', type=int, default=50)
    p.add_argument('--camera-samples', type=int, default=16, help='SPPM: camera rays per pixel and pass')
    p.add_argument('--pm-photons', type=int, default=20000, help='photon map: global map photons (4x for caustics)')
    p.add_argument('--gather', type=int, default=16, help='photon map: final gather rays')
    p.add_argument('--reference', choices=('path', 'sppm'),
                   help='path: each renderer against its own path-traced reference (default); sppm: every renderer '
                        'against one long glint SPPM run (default for scenes lit by a point light, whose caustics no '
                        'path tracer samples)')
    p.add_argument('--ref-seconds', type=float, default=120, help='--reference sppm: seconds of SPPM per half')
    p.add_argument('--no-cycles', action='store_true', help='glint only')
    p.add_argument('--quick', action='store_true', help='32x32, budgets 1, reference 1024 spp')
    p.add_argument('--glint', default=os.path.join(pc.ROOT, 'build', 'examples', 'glint-render'))
    p.add_argument('--blender', default=shutil.which('blender') or '')
    p.add_argument('--core', type=int, default=0, help='CPU core every render is pinned to')
    p.add_argument('--work', default=os.path.join(pc.ROOT, 'build', 'caustics_table'))
    p.add_argument('--json', help='write the rows here')
    a = p.parse_args()
    if pc.np is None:
        print('caustics_table: skipped: numpy is not installed (Debian: apt-get install python3-numpy)')
        return 0
    if a.quick:
        a.size, a.budgets, a.ref_spp, a.ref_seconds = 32, '1', 1024, 4
    if a.scene not in pc.SCENES:
        sys.exit('caustics_table: unknown scene %r (known: %s)' % (a.scene, ', '.join(pc.SCENES)))
    cycles = not a.no_cycles and a.blender and os.path.exists(a.blender)
    if not a.no_cycles and not cycles:
        print('caustics_table: Blender is not installed (Debian: apt-get install blender): glint rows only')
    a.bunny = ''
    a.reps = 1
    rn = pc.Runner(a)
    work = os.path.join(a.work, '%s_%d' % (a.scene, a.size))
    os.makedirs(work, exist_ok=True)
    sj = os.path.join(work, 'scene.json')
    pc.run([a.glint] + pc.SCENES[a.scene] + ['--size', str(a.size), '--export-scene', sj])
    if a.reference is None:
        a.reference = 'sppm' if a.scene.endswith('-point') else 'path'
    print('%s %dx%d, one thread on core %d; references %s%s'
          % (a.scene, a.size, a.size, a.core, '%d spp (two halves)' % a.ref_spp if a.reference == 'path'
             else 'glint SPPM, two halves of %g s' % a.ref_seconds, '' if cycles else '; no Cycles'), flush=True)
    refs = references(rn, a, sj, work, cycles) if a.reference == 'path' else sppm_reference(rn, a, work)
    keep = light_mask(json.load(open(sj)), a.size)
    rows = []
    for budget in [float(b) for b in a.budgets.split(',')]:
        for name, flags in GLINT_METHODS.items():
            extra = [f.format(photons=a.photons, pm_photons=a.pm_photons, radius=a.radius, knn=a.knn, gather=a.gather,
                              camera=a.camera_samples)
                     for f in flags]
            path = os.path.join(work, 'glint_%s_%g.exr' % (name, budget))
            img, t = rn.glint(a.scene, 1, 1, path, extra + ['--time-budget', str(budget)])
            rows.append({'budget': budget, 'method': 'glint ' + name, 'cpu': t['cpu'], 'rmse': rmse(img, refs['glint'], keep),
                         'rmse_image': rmse(img, refs['glint'])})
            print_row(rows[-1])
        if cycles:
            path = os.path.join(work, 'cycles_%g.exr' % budget)
            img, t = rn.cycles(sj, 1 << 20, 1, path, time_limit=budget)
            ref = refs.get('cycles', refs['glint'])
            rows.append({'budget': budget, 'method': 'Cycles 3.4 path', 'cpu': t['cpu'], 'rmse': rmse(img, ref, keep),
                         'rmse_image': rmse(img, ref)})
            print_row(rows[-1])
    print('\n| budget s | method | CPU s | RMSE (no light) | / glint path | / Cycles | RMSE (image) |')
    print('|---|---|---|---|---|---|---|')
    for r in rows:
        base = next(x for x in rows if x['budget'] == r['budget'] and x['method'] == 'glint path')
        cyc = next((x for x in rows if x['budget'] == r['budget'] and x['method'].startswith('Cycles')), None)
        print('| %g | %s | %.2f | %.4f | %.2f | %s | %.4f |'
              % (r['budget'], r['method'], r['cpu'], r['rmse'], r['rmse'] / base['rmse'],
                 '%.2f' % (r['rmse'] / cyc['rmse']) if cyc else '-', r['rmse_image']))
    if a.json:
        json.dump({'scene': a.scene, 'size': a.size, 'ref_spp': a.ref_spp, 'rows': rows}, open(a.json, 'w'), indent=1)
    return 0


def references(rn, a, sj, work, cycles):
    """Each renderer's path-traced reference as (mean, (half 0, half 1)), cached in `work`."""
    half = a.ref_spp // 2
    out = {}
    for name in ('glint', 'cycles') if cycles else ('glint',):
        halves = []
        for k, seed in enumerate((1000001, 1000002)):
            path = os.path.join(work, 'ref_%s_%d_%d.exr' % (name, half, k))
            make = ((lambda p, s=seed: rn.glint(a.scene, half, s, p, [])) if name == 'glint'
                    else (lambda p, s=seed: rn.cycles(sj, half, s, p)))
            t0 = time.time()
            img, t = pc.cached(path, make)
            halves.append(img)
            print('  reference %-6s half %d: %d spp, %.1f s CPU%s'
                  % (name, k, half, t['cpu'], '' if time.time() - t0 > 1 else ' (cached)'), flush=True)
        out[name] = ((halves[0] + halves[1]) / 2, halves)
    return out


def sppm_reference(rn, a, work):
    """One long glint SPPM run as two halves of --ref-seconds each (seeds apart), cached in `work`:
    every renderer's reference. SPPM is consistent, not unbiased: what bias is left after the
    halves' passes counts as the reference's error, not the methods'."""
    flags = [f.format(photons=a.photons, radius=a.radius, camera=a.camera_samples) for f in GLINT_METHODS['sppm']]
    halves = []
    for k, seed in enumerate((1000001, 1000002)):
        path = os.path.join(work, 'ref_sppm_%g_%d.exr' % (a.ref_seconds, k))
        t0 = time.time()
        img, t = pc.cached(path, lambda p, s=seed: rn.glint(a.scene, 1, s, p, flags + ['--time-budget', str(a.ref_seconds)]))
        halves.append(img)
        print('  reference glint SPPM half %d: %.0f s, %.1f s CPU%s'
              % (k, a.ref_seconds, t['cpu'], '' if time.time() - t0 > 1 else ' (cached)'), flush=True)
    return {'glint': ((halves[0] + halves[1]) / 2, halves)}


def print_row(r):
    print('  %4g s  %-16s CPU %6.2f s  RMSE %.4f (image %.4f)' % (r['budget'], r['method'], r['cpu'], r['rmse'], r['rmse_image']),
          flush=True)


if __name__ == '__main__':
    sys.exit(main())
