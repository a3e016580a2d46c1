#!/usr/bin/env python3
"""Peer comparison: glint-render against Blender's Cycles on the same scene, one thread.

    python3 tools/peer_cycles.py                        # cornell, cornell-glossy, cornell-bunny, 128^2
    python3 tools/peer_cycles.py --quick                # a smoke run (small ladder and reference)
    python3 tools/peer_cycles.py --scenes cornell --glint-args "--roulette classic"

Needs python3 with numpy (Debian python3-numpy), a built glint-render (build/examples) and
Blender with Cycles (Debian `apt-get install blender`, 3.4). Without Blender (or numpy) it says
so and exits 0, as the Embree comparisons are skipped where Embree is missing.

What it does, per scene:
  1. glint-render --export-scene writes the built scene (its triangles in the tracer's order,
     per-triangle materials, the area light, the camera, size and max_depth) as JSON;
     `cornell-bunny` is `--scene cornell --insert-mesh BUNNY` (the Stanford bunny on the
     box's free floor).
  2. This same file, run inside Blender (`blender -b --factory-startup -t 1 --python THIS --
     --job JOB.json`), builds that scene with bpy: one mesh with the same triangles (same
     winding, flat shading), Lambert diffuse (Diffuse BSDF, roughness 0), emission on the front
     face only (Mix by Geometry > Backfacing: emission + diffuse in front, diffuse behind),
     the same pinhole camera (vertical fov, square pixels), black world; Cycles on the CPU,
     box pixel filter 1 px wide (glint's uniformly jittered pixel), bounce limits equal to
     glint's max_depth for every kind, no denoising, no adaptive sampling, no clamping, no
     glossy filter, caustics on, light threshold 0, no path guiding, no motion blur, 1 thread.
     Cycles 3.4 has no light tree (it came in 3.5). Cycles' sampling pattern and roulette are
     its defaults (progressive multi-jitter; throughput roulette).
  3. Region masks: the triangle hit by each pixel centre's ray (Blender's ray_cast, with
     glint's camera formula), triangles classified into floor, ceiling, back, left (red) and
     right (green) walls, the light and the bunny; a pixel counts if its 4 neighbours hit the
     same region.
  4. Renders, every one pinned with `taskset -c CORE`, the two renderers alternating: each
     renderer's reference as two halves of REF/2 spp with different seeds, then the spp
     ladder (64, 256, 1024) REPS times.
  5. Prints region means of the two references with standard errors (agreement) and, at each
     spp, MSE against the renderer's own reference minus that reference's noise (the mean of
     (A - B)^2 / 4 over pixels and bands, A and B its halves), seconds, MSE*spp, and the
     equal-error time ratio glint / Cycles = (MSE_glint t_glint) / (MSE_cycles t_cycles).

Times: CPU seconds, because the 2-core machine this runs on is shared and wall times under
load are several times the CPU time. glint's is the glint-render process's user + system time
(os.wait4): its render, tree build, scene set-up and EXR write (a whole 1-spp run takes
0.02-0.04 s CPU at 128^2). Cycles' is Blender's process time measured inside Blender around
bpy.ops.render.render(): Cycles' scene sync, BVH build and render, not Blender's start-up, our
scene building or the EXR write. Wall times (glint-render's printed render + build time, and
Blender's around the same call) are kept too and their ratio printed beside. "walls" MSE is
over the region pixels other than the light: light transport without the light's edges.
EXR files (glint-render's and Cycles', both ZIP) are read by tools/exr.py.

Run it with Debian's /usr/bin/python3 (where python3-numpy lives) if another python3 comes
first on PATH.

The glossy scene: glint's lobe is the energy-normalized Phong lobe about the mirror direction
(ks (n+2)/(2 pi) cos^n, tracer/brdf.hpp). Cycles 3.4 has no such lobe in its node shaders (the
Phong-ramp closure exists only in OSL, which Debian's build lacks), so cornell-glossy is
exported with the nearest cosine-power lobe Cycles has, Ashikhmin-Shirley (a Blinn-Phong lobe
about the half vector) with exponent 4n (roughness sqrt(sqrt(2 / (4n + 2)))): the two images
differ (the region means show by how much), each renderer's error is still against its own
reference, so the time ratio compares how each renders a glossy Cornell box, not one image.

The caustic scenes (cornell-caustics, cornell-caustics-point: a glass sphere and a mirror cube
in the Cornell box): the dielectric is Cycles' Glass BSDF with the sharp distribution (the ideal
dielectric, glint's MaterialKind::dielectric), the mirror its Glossy BSDF, sharp; caustics are
on (reflective and refractive), as for every scene. The point light is a Blender point light of
radius 0. Region masks leave the sphere and the cube out (they belong to no region; 'image'
keeps every pixel). tools/caustics_table.py compares glint's photon integrators on them.
"""
import argparse
import hashlib
import json
import math
import os
import re
import shlex
import shutil
import subprocess
import sys
import time

try:
    import numpy as np
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import exr  # tools/exr.py
except ImportError:  # numpy is checked in main(), so that the message is clear
    np = None

REGIONS = ['floor', 'ceiling', 'back', 'left', 'right', 'light', 'bunny', 'image']
SCENES = {
    'cornell': ['--scene', 'cornell'],
    'cornell-glossy': ['--scene', 'cornell-glossy'],
    'cornell-bunny': ['--scene', 'cornell', '--insert-mesh', '{bunny}'],
    'cornell-caustics': ['--scene', 'cornell-caustics'],
    'cornell-caustics-point': ['--scene', 'cornell-caustics-point'],
    'hall': ['--scene', 'hall'],
    'kitchen': ['--scene', 'kitchen'],
}
# Scenes that are not Cornell boxes have one region, 'image': every pixel whose 4 neighbours
# hit geometry too.
CORNELL = ('cornell', 'cornell-glossy', 'cornell-bunny', 'cornell-caustics', 'cornell-caustics-point')
HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def read_rgb(path):
    return exr.rgb_of(exr.read_exr(path)).astype(np.float64)


# ---------------------------------------------------------------------------------------------
# Inside Blender: build the scene from the JSON export and render it, or cast the mask rays.

def glint_camera_dirs(cam, w, h, sx, sy):
    """Directions of glint's Camera::ray (tracer/scene.hpp) for film points sx, sy in [0,1]."""
    eye, target, up = (np.array(cam[k], float) for k in ('eye', 'target', 'up'))
    wv = (target - eye) / np.linalg.norm(target - eye)
    u = np.cross(wv, up)
    u /= np.linalg.norm(u)
    v = np.cross(u, wv)
    t = math.tan(cam['fov_y'] * 0.5)
    d = (wv + u * ((2 * sx - 1) * t * (w / h))[..., None] + v * ((1 - 2 * sy) * t)[..., None])
    return eye, wv, u, v, d / np.linalg.norm(d, axis=-1, keepdims=True)


def blender_material(bpy, name, m):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new('ShaderNodeOutputMaterial')
    kind, kd, ks = m['kind'], m['kd'], m['ks']

    def bsdf(node_type, color, **inputs):
        n = nt.nodes.new(node_type)
        n.inputs['Color'].default_value = (*color, 1.0)
        for k, v in inputs.items():
            n.inputs[k].default_value = v
        return n

    def add(a, b):
        n = nt.nodes.new('ShaderNodeAddShader')
        nt.links.new(a.outputs[0], n.inputs[0])
        nt.links.new(b.outputs[0], n.inputs[1])
        return n

    if kind == 'lambertian':
        surf = bsdf('ShaderNodeBsdfDiffuse', kd, Roughness=0.0)
    elif kind == 'glossy':
        gl = bsdf('ShaderNodeBsdfGlossy', ks, Roughness=(2.0 / (4.0 * m['exponent'] + 2.0)) ** 0.25)
        gl.distribution = 'ASHIKHMIN_SHIRLEY'
        surf = add(bsdf('ShaderNodeBsdfDiffuse', kd, Roughness=0.0), gl)
    elif kind == 'mirror':
        surf = bsdf('ShaderNodeBsdfGlossy', ks, Roughness=0.0)
        surf.distribution = 'SHARP'
    else:
        surf = bsdf('ShaderNodeBsdfGlass', (1.0, 1.0, 1.0), IOR=m['ior'], Roughness=0.0)
        surf.distribution = 'SHARP'
    if max(m['emission']) > 0:
        e = nt.nodes.new('ShaderNodeEmission')
        s = max(m['emission'])
        e.inputs['Color'].default_value = (*[c / s for c in m['emission']], 1.0)
        e.inputs['Strength'].default_value = s
        front = add(e, surf)
        back = surf if kind != 'lambertian' else bsdf('ShaderNodeBsdfDiffuse', kd, Roughness=0.0)
        mix = nt.nodes.new('ShaderNodeMixShader')
        geo = nt.nodes.new('ShaderNodeNewGeometry')
        nt.links.new(geo.outputs['Backfacing'], mix.inputs['Fac'])
        nt.links.new(front.outputs[0], mix.inputs[1])  # Fac 0: front face
        nt.links.new(back.outputs[0], mix.inputs[2])   # Fac 1: back face, no emission
        surf = mix
    nt.links.new(surf.outputs[0], out.inputs['Surface'])
    return mat


def blender_point_light(bpy, sc, i, l):
    """A glint PointLight (lights/light.hpp) as a Blender light of radius 0. Cycles 3.4's point
    light of power P has intensity P / (4 pi) in every direction, and its spot light the same
    times cos(theta) times a smoothstep over the blend region, which is glint's spot profile
    (both measured with a Blender render of a plane under the light, to 0.2%). Cycles has no
    cosine (oriented) point light."""
    from mathutils import Vector
    if l['kind'] == 'cosine':
        sys.exit('peer_cycles: point light %d is a cosine (oriented) light, which Cycles 3.4 has no light for' % i)
    peak = max(l['intensity'])
    data = bpy.data.lights.new('light%d' % i, type='SPOT' if l['kind'] == 'spot' else 'POINT')
    data.energy = 4 * math.pi * peak
    data.color = [c / peak if peak > 0 else 0.0 for c in l['intensity']]
    data.shadow_soft_size = 0.0
    if l['kind'] == 'spot':
        co, ci = l['cos_outer'], l['cos_inner']
        data.spot_size = 2 * math.acos(co)
        data.spot_blend = (ci - co) / (1 - co) if co < 1 else 0.0
    obj = bpy.data.objects.new('light%d' % i, data)
    obj.location = l['position']
    # Blender's spot shines along its local -Z.
    obj.rotation_mode = 'QUATERNION'
    obj.rotation_quaternion = Vector([-c for c in l['axis']]).to_track_quat('Z', 'Y')
    sc.collection.objects.link(obj)


def blender_build(bpy, scene_json):
    from mathutils import Matrix
    sc = bpy.context.scene
    for o in list(bpy.data.objects):  # the factory scene's cube, light and camera
        bpy.data.objects.remove(o)
    if any(m.get('kd_texture', -1) >= 0 for m in scene_json['materials']):
        sys.exit('peer_cycles: the scene has textured materials, which this exporter does not hand to Cycles')
    tris = np.array(scene_json['triangles'], float).reshape(-1, 3, 3)
    mesh = bpy.data.meshes.new('glint')
    mesh.from_pydata(tris.reshape(-1, 3).tolist(), [], [[3 * i, 3 * i + 1, 3 * i + 2] for i in range(len(tris))])
    for i, m in enumerate(scene_json['materials']):
        mesh.materials.append(blender_material(bpy, 'm%d' % i, m))
    mesh.polygons.foreach_set('material_index', scene_json['material_of'])
    normals = scene_json.get('corner_normals')  # glint's shading normals, per triangle corner
    mesh.polygons.foreach_set('use_smooth', [normals is not None] * len(tris))
    mesh.update()
    if normals is not None:  # one loop per corner, in the triangles' order (Blender 3.x custom split normals)
        mesh.use_auto_smooth = True
        mesh.normals_split_custom_set(np.array(normals, float).reshape(-1, 3).tolist())
        mesh.update()
    obj = bpy.data.objects.new('glint', mesh)
    sc.collection.objects.link(obj)
    cam = scene_json['camera']
    cd = bpy.data.cameras.new('cam')
    cd.sensor_fit = 'VERTICAL'
    cd.angle_y = cam['fov_y']
    cd.clip_start, cd.clip_end = 1e-3, 1e4
    co = bpy.data.objects.new('cam', cd)
    eye, wv, u, v, _ = glint_camera_dirs(cam, 1, 1, np.zeros(1), np.zeros(1))
    m = Matrix.Identity(4)
    for r in range(3):
        m[r][0], m[r][1], m[r][2], m[r][3] = u[r], v[r], -wv[r], eye[r]
    co.matrix_world = m
    sc.collection.objects.link(co)
    sc.camera = co
    for i, l in enumerate(scene_json.get('point_lights', [])):
        blender_point_light(bpy, sc, i, l)
    world = bpy.data.worlds.new('black')
    world.use_nodes = True
    world.node_tree.nodes['Background'].inputs['Strength'].default_value = 0.0
    sc.world = world
    return sc


def blender_settings(sc, job, scene_json):
    r, c = sc.render, sc.cycles
    r.engine = 'CYCLES'
    c.device = 'CPU'
    r.resolution_x, r.resolution_y = scene_json['width'], scene_json['height']
    r.resolution_percentage = 100
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0
    r.threads_mode, r.threads = 'FIXED', 1
    r.use_motion_blur = False
    r.use_compositing = r.use_sequencer = False
    r.film_transparent = False
    c.pixel_filter_type, c.filter_width = 'BOX', 1.0
    c.samples = job['spp']
    if job.get('time_limit'):  # equal-time runs: samples until the limit (tools/caustics_table.py)
        c.time_limit = job['time_limit']
    c.seed = job['seed']
    c.use_animated_seed = False
    c.use_adaptive_sampling = False
    c.use_denoising = False
    sc.view_layers[0].cycles.denoising_store_passes = False
    c.sample_clamp_direct = c.sample_clamp_indirect = 0.0
    c.blur_glossy = 0.0
    c.caustics_reflective = c.caustics_refractive = True
    c.light_sampling_threshold = 0.0
    if hasattr(c, 'use_guiding'):
        c.use_guiding = False
    depth = scene_json['max_depth']
    c.max_bounces = c.diffuse_bounces = c.glossy_bounces = c.transmission_bounces = depth
    c.volume_bounces, c.transparent_max_bounces = 0, depth
    c.use_auto_tile = False
    sc.view_settings.view_transform, sc.view_settings.look = 'Standard', 'None'
    sc.view_settings.exposure, sc.view_settings.gamma = 0.0, 1.0
    r.image_settings.file_format = 'OPEN_EXR'
    r.image_settings.color_depth = '32'
    r.image_settings.color_mode = 'RGB'
    r.image_settings.exr_codec = 'ZIP'


def blender_mask(bpy, sc, scene_json, path):
    """Index of the triangle hit by each pixel centre's ray (-1 for none), glint's camera."""
    w, h = scene_json['width'], scene_json['height']
    sx, sy = np.meshgrid((np.arange(w) + 0.5) / w, (np.arange(h) + 0.5) / h)
    eye, _, _, _, d = glint_camera_dirs(scene_json['camera'], w, h, sx, sy)
    dg = bpy.context.evaluated_depsgraph_get()
    ids = np.full((h, w), -1, np.int64)
    for y in range(h):
        for x in range(w):
            hit, _, _, index, obj, _ = sc.ray_cast(dg, tuple(eye), tuple(d[y, x]))
            if hit and obj.name == 'glint':
                ids[y, x] = index
    np.save(path, ids)


def blender_export_gltf(bpy, sc, scene_json, path):
    """The built scene as a glTF 2.0 binary (Blender's own exporter), its materials first made
    Principled BSDFs, which the exporter writes as metallic-roughness: Lambertian as base
    colour kd, metallic 0, roughness 1; mirror as base colour ks, metallic 1, roughness 0;
    emission as the emission colour and strength. Coordinates stay glint's (no Y-up turn)."""
    for i, m in enumerate(scene_json['materials']):
        if m['kind'] not in ('lambertian', 'mirror'):
            sys.exit('peer_cycles: material %d is %s, which the glTF export does not map' % (i, m['kind']))
        mat = bpy.data.materials['m%d' % i]
        nt = mat.node_tree
        nt.nodes.clear()
        out = nt.nodes.new('ShaderNodeOutputMaterial')
        b = nt.nodes.new('ShaderNodeBsdfPrincipled')
        mirror = m['kind'] == 'mirror'
        b.inputs['Base Color'].default_value = (*(m['ks'] if mirror else m['kd']), 1.0)
        b.inputs['Metallic'].default_value = 1.0 if mirror else 0.0
        b.inputs['Roughness'].default_value = 0.0 if mirror else 1.0
        peak = max(m['emission'])
        if peak > 0:
            b.inputs['Emission'].default_value = (*[c / peak for c in m['emission']], 1.0)
            b.inputs['Emission Strength'].default_value = peak
        nt.links.new(b.outputs[0], out.inputs['Surface'])
    sc.render.resolution_x, sc.render.resolution_y = scene_json['width'], scene_json['height']
    bpy.ops.export_scene.gltf(filepath=path, export_format='GLB', export_yup=False, export_cameras=True,
                              export_lights=True)


def blender_main(argv):
    import bpy
    job = json.load(open(argv[argv.index('--job') + 1]))
    scene_json = json.load(open(job['scene']))
    sc = blender_build(bpy, scene_json)
    if job.get('gltf'):
        blender_export_gltf(bpy, sc, scene_json, job['gltf'])
        return
    blender_settings(sc, job, scene_json)
    if job.get('mask'):
        blender_mask(bpy, sc, scene_json, job['mask'])
        return
    t0, c0 = time.perf_counter(), time.process_time()
    bpy.ops.render.render(write_still=False)
    t1, c1 = time.perf_counter(), time.process_time()
    bpy.data.images['Render Result'].save_render(job['out'], scene=sc)
    with open(job['out'] + '.json', 'w') as f:
        json.dump({'seconds': t1 - t0, 'cpu_seconds': c1 - c0}, f)


# ---------------------------------------------------------------------------------------------
# The driver.

def run(cmd, rusage=False):
    """Output of `cmd` (exits on failure); with rusage, also the child's CPU seconds."""
    with subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True) as p:
        out = p.stdout.read()
        _, status, ru = os.wait4(p.pid, 0)
        p.returncode = os.waitstatus_to_exitcode(status)
    if p.returncode != 0:
        sys.exit('peer_cycles: command failed (%d): %s\n%s' % (p.returncode, ' '.join(cmd), out[-4000:]))
    return (out, ru.ru_utime + ru.ru_stime) if rusage else out


class Runner:
    def __init__(self, a):
        self.a = a
        self.pin = ['taskset', '-c', str(a.core)] if shutil.which('taskset') else []

    def glint(self, scene, spp, seed, out, extra):
        cmd = self.pin + [self.a.glint] + [s.format(bunny=self.a.bunny) for s in SCENES[scene]] + [
            '--size', str(self.a.size), '--spp', str(spp), '--seed', str(seed), '--threads', '1', '--out', out] + extra
        text, cpu = run(cmd, rusage=True)
        m = re.search(r'rendered .* in ([0-9.]+) s \(build (?:\S+ )?([0-9.]+) s\)', text)
        if not m:
            sys.exit('peer_cycles: cannot read the time from glint-render:\n' + text)
        return read_rgb(out), {'cpu': cpu, 'wall': float(m.group(1)) + float(m.group(2))}

    def blender(self, job_path):
        return run(self.pin + [self.a.blender, '-b', '--factory-startup', '-t', '1', '--python', os.path.abspath(__file__),
                               '--', '--job', job_path])

    def cycles(self, scene_json, spp, seed, out, time_limit=0):
        job = out + '.job.json'
        json.dump({'scene': scene_json, 'spp': spp, 'seed': seed, 'out': out, 'time_limit': time_limit}, open(job, 'w'))
        self.blender(job)
        t = json.load(open(out + '.json'))
        return read_rgb(out), {'cpu': t['cpu_seconds'], 'wall': t['seconds']}


def classify(scene_json, ids, inserted, cornell=True):
    """Region label per pixel (index into REGIONS, -1 none) from the hit triangle indices."""
    if not cornell:
        return neighbours_agree(np.where(ids >= 0, REGIONS.index('image'), -1))
    tris = np.array(scene_json['triangles'], float).reshape(-1, 3, 3)
    mats = scene_json['materials']
    mat_of = np.array(scene_json['material_of'])
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
    lo, hi = tris.min(axis=1), tris.max(axis=1)
    emissive = np.array([max(m['emission']) > 0 for m in mats])[mat_of]
    label = np.full(len(tris), -1)
    flat_y, flat_z, flat_x = abs(n[:, 1]) > 0.9, abs(n[:, 2]) > 0.9, abs(n[:, 0]) > 0.9
    label[flat_y & (hi[:, 1] < 0.01)] = REGIONS.index('floor')
    label[flat_y & (lo[:, 1] > 1.985)] = REGIONS.index('ceiling')
    label[flat_z & (hi[:, 2] < -1.03)] = REGIONS.index('back')
    label[flat_x & (hi[:, 0] < -0.98)] = REGIONS.index('left')
    label[flat_x & (lo[:, 0] > 0.99)] = REGIONS.index('right')
    label[emissive] = REGIONS.index('light')
    if inserted:
        label[mat_of == len(mats) - 1] = REGIONS.index('bunny')
    return neighbours_agree(np.where(ids >= 0, label[np.maximum(ids, 0)], -1))


def neighbours_agree(px):
    """The labels `px` where a pixel's 4 neighbours carry its label, else -1."""
    keep = px.copy()
    keep[1:-1, 1:-1] = np.where((px[1:-1, 1:-1] == px[:-2, 1:-1]) & (px[1:-1, 1:-1] == px[2:, 1:-1]) &
                                (px[1:-1, 1:-1] == px[1:-1, :-2]) & (px[1:-1, 1:-1] == px[1:-1, 2:]), px[1:-1, 1:-1], -1)
    keep[0, :] = keep[-1, :] = keep[:, 0] = keep[:, -1] = -1
    return keep


def cached(path, make):
    if os.path.exists(path) and os.path.exists(path + '.t'):
        return read_rgb(path), json.load(open(path + '.t'))
    img, t = make(path)
    json.dump(t, open(path + '.t', 'w'))
    return img, t


def references(rn, a, scene, scene_json, work):
    """Each renderer's reference as two halves; glint's with its default policies (no
    --glint-args), so that one reference serves every option compared."""
    half = a.ref_spp // 2
    out = {'glint': [], 'cycles': []}
    for k, seed in enumerate((1000001, 1000002)):
        g = os.path.join(work, 'ref_glint_%d_%d.exr' % (half, k))
        c = os.path.join(work, 'ref_cycles_%d_%d.exr' % (half, k))
        for name, path, make in (('glint', g, lambda p, s=seed: rn.glint(scene, half, s, p, [])),
                                 ('cycles', c, lambda p, s=seed: rn.cycles(scene_json, half, s, p))):
            t0 = time.time()
            img, t = cached(path, make)
            out[name].append(img)
            print('  reference %-6s half %d: %d spp, %.1f s CPU, %.1f s wall%s'
                  % (name, k, half, t['cpu'], t['wall'], '' if time.time() - t0 > 1 else ' (cached)'), flush=True)
    return {k: ((v[0] + v[1]) / 2, v) for k, v in out.items()}


def region_table(labels, refs, inserted):
    print('  region means of the references (mean of R, G, B; standard error from the two halves):')
    print('    %-8s %6s  %-20s %-20s %9s %6s' % ('region', 'pixels', 'glint', 'Cycles', 'diff', 'z'))
    rows = []
    for i, name in enumerate(REGIONS):
        if name == 'bunny' and not inserted:
            continue
        m = labels == i
        if not m.any():
            continue
        stats = {}
        for k, (ref, halves) in refs.items():
            mean = ref[m].mean()
            se = math.sqrt(np.sum(((halves[0] - halves[1])[m].mean(axis=-1)) ** 2) / 4) / m.sum()
            stats[k] = (mean, se)
        (gm, gs), (cm, cs) = stats['glint'], stats['cycles']
        z = (gm - cm) / math.hypot(gs, cs)
        rows.append({'region': name, 'pixels': int(m.sum()), 'glint': gm, 'glint_se': gs, 'cycles': cm, 'cycles_se': cs, 'z': z})
        print('    %-8s %6d  %.5f +- %.5f  %.5f +- %.5f %+8.3f%% %+6.2f' % (name, m.sum(), gm, gs, cm, cs, 100 * (gm / cm - 1), z))
    return rows


def mse(img, ref, mask=None):
    """MSE of `img` against the reference (mean, halves) over the pixels of `mask` (all if
    None) and the three bands, minus the reference's own variance there, mean((A - B)^2) / 4."""
    mean, (h0, h1) = ref
    sel = (lambda x: x) if mask is None else (lambda x: x[mask])
    return float(np.mean(sel((img - mean) ** 2)) - np.mean(sel((h0 - h1) ** 2)) / 4)


def ladder(rn, a, scene, scene_json, work, refs, extra, walls):
    """The spp ladder, the renderers alternating; MSE over the whole image and over `walls`
    (the region pixels other than the light: light transport without the light's edges)."""
    rows = []
    tag = hashlib.sha1(' '.join(extra).encode()).hexdigest()[:8]
    for rep in range(a.reps):
        for spp in a.ladder:
            r = {'rep': rep, 'spp': spp}
            for name in ('glint', 'cycles'):  # alternating, one after the other at each spp
                path = os.path.join(work, '%s_%s_%d_%d.exr' % (name, tag, spp, rep))
                img, t = (rn.glint(scene, spp, 1 + rep, path, extra) if name == 'glint'
                          else rn.cycles(scene_json, spp, 1 + rep, path))
                json.dump(t, open(path + '.t', 'w'))
                r.update({'mse_' + name: mse(img, refs[name]), 'mse_walls_' + name: mse(img, refs[name], walls),
                          'cpu_' + name: t['cpu'], 'wall_' + name: t['wall']})
            for key, m in (('ratio', 'mse_'), ('ratio_walls', 'mse_walls_')):
                r[key] = (r[m + 'glint'] * r['cpu_glint']) / (r[m + 'cycles'] * r['cpu_cycles'])
            r['ratio_wall_clock'] = (r['mse_glint'] * r['wall_glint']) / (r['mse_cycles'] * r['wall_cycles'])
            rows.append(r)
            print('  %5d spp  glint MSE %.3e (*spp %.4f) %6.2f s   Cycles MSE %.3e (*spp %.4f) %6.2f s   '
                  'MSE*t glint/Cycles %.2f (walls %.2f; wall-clock %.2f)'
                  % (spp, r['mse_glint'], r['mse_glint'] * spp, r['cpu_glint'], r['mse_cycles'], r['mse_cycles'] * spp,
                     r['cpu_cycles'], r['ratio'], r['ratio_walls'], r['ratio_wall_clock']), flush=True)
    return rows


def comparison(rn, a, scene):
    work = os.path.join(a.work, '%s_%d' % (scene, a.size))
    os.makedirs(work, exist_ok=True)
    sj = os.path.join(work, 'scene.json')
    run([a.glint] + [s.format(bunny=a.bunny) for s in SCENES[scene]] + ['--size', str(a.size), '--export-scene', sj])
    scene_json = json.load(open(sj))
    print('%s: %d triangles, %d materials, %dx%d, max_depth %d; reference %d spp (two halves), ladder %s x %d'
          % (scene, len(scene_json['triangles']), len(scene_json['materials']), a.size, a.size, scene_json['max_depth'],
             a.ref_spp, a.ladder, a.reps), flush=True)
    mask = os.path.join(work, 'hits.npy')
    if not os.path.exists(mask):
        job = os.path.join(work, 'mask.job.json')
        json.dump({'scene': sj, 'spp': 1, 'seed': 0, 'mask': mask}, open(job, 'w'))
        rn.blender(job)
    labels = classify(scene_json, np.load(mask), 'insert-mesh' in ' '.join(SCENES[scene]), scene in CORNELL)
    refs = references(rn, a, scene, sj, work)
    regions = region_table(labels, refs, scene == 'cornell-bunny')
    walls = (labels >= 0) & (labels != REGIONS.index('light'))
    rows = ladder(rn, a, scene, sj, work, refs, shlex.split(a.glint_args), walls)
    ratios = [r['ratio'] for r in rows]
    print('  equal-error time glint / Cycles: geometric mean %.2f, range %.2f-%.2f (< 1: glint is faster)'
          % (math.exp(np.mean(np.log(ratios))), min(ratios), max(ratios)), flush=True)
    for key in ('ratio_walls', 'ratio_wall_clock'):
        print('    %s: geometric mean %.2f' % (key, math.exp(np.mean(np.log([r[key] for r in rows])))))
    return {'scene': scene, 'size': a.size, 'ref_spp': a.ref_spp, 'glint_args': a.glint_args, 'regions': regions, 'ladder': rows}


def image_mean(path):
    """Per band: the image mean of a glint-render EXR and its standard error from the
    per-pixel variance layer."""
    ch = exr.read_exr(path)
    img, var = exr.rgb_of(ch).astype(np.float64), exr.rgb_of(ch, 'variance').astype(np.float64)
    n = img.shape[0] * img.shape[1]
    return img.reshape(-1, 3).mean(axis=0), np.sqrt(var.reshape(-1, 3).sum(axis=0)) / n


def gltf_check(rn, a, scene, spp=64):
    """Blender exports `scene` (built from glint's JSON) as glTF; glint-render renders that
    file and the built-in scene with different seeds; prints the image means, their difference
    in standard errors, and the camera each run printed."""
    work = os.path.join(a.work, 'gltf_%s_%d' % (scene, a.size))
    os.makedirs(work, exist_ok=True)
    sj, glb = os.path.join(work, 'scene.json'), os.path.join(work, scene + '.glb')
    run([a.glint] + SCENES[scene] + ['--size', str(a.size), '--export-scene', sj])
    job = os.path.join(work, 'gltf.job.json')
    json.dump({'scene': sj, 'gltf': glb}, open(job, 'w'))
    rn.blender(job)
    runs = {}
    for name, src, seed in (('built-in', SCENES[scene], 1), ('glTF', ['--scene-file', glb], 2)):
        out = os.path.join(work, name.replace('-', '') + '.exr')
        text = run(rn.pin + [a.glint] + src + ['--size', str(a.size), '--spp', str(spp), '--seed', str(seed),
                                                '--sampler', 'random', '--threads', '1', '--out', out])
        runs[name] = image_mean(out)
        print('  %s: %s' % (name, next(l for l in text.splitlines() if l.startswith('camera:'))))
    (m1, s1), (m2, s2) = runs['built-in'], runs['glTF']
    z = (m2 - m1) / np.sqrt(s1 ** 2 + s2 ** 2)
    print('%s from Blender glTF %s: image mean R G B %s (built-in %s), %s standard errors apart, %dx%d, %d spp'
          % (scene, glb, np.round(m2, 5), np.round(m1, 5), np.round(z, 2), a.size, a.size, spp), flush=True)
    return float(np.abs(z).max())


def markdown(results):
    """The results as the Markdown tables of docs/tracer.md."""
    print('\n| scene | spp | glint MSE·spp | glint s | Cycles MSE·spp | Cycles s | glint / Cycles, image | walls | wall-clock |')
    print('|---|---|---|---|---|---|---|---|---|')
    for res in results:
        for r in res['ladder']:
            print('| %s | %d | %.4f | %.2f | %.4f | %.2f | **%.2f** | %.2f | %.2f |'
                  % (res['scene'], r['spp'], r['mse_glint'] * r['spp'], r['cpu_glint'], r['mse_cycles'] * r['spp'],
                     r['cpu_cycles'], r['ratio'], r['ratio_walls'], r['ratio_wall_clock']))
    print('\n| scene | region | pixels | glint | Cycles | difference | z |')
    print('|---|---|---|---|---|---|---|')
    for res in results:
        for g in res['regions']:
            print('| %s | %s | %d | %.5f ± %.5f | %.5f ± %.5f | %+.3f%% | %+.1f |'
                  % (res['scene'], g['region'], g['pixels'], g['glint'], g['glint_se'], g['cycles'], g['cycles_se'],
                     100 * (g['glint'] / g['cycles'] - 1), g['z']))


def main():
    p = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    p.add_argument('--scenes', default='cornell,cornell-glossy,cornell-bunny')
    p.add_argument('--size', type=int, default=128)
    p.add_argument('--ladder', default='64,256,1024')
    p.add_argument('--ref-spp', type=int, default=8192, help='reference spp (rendered as two halves)')
    p.add_argument('--reps', type=int, default=1, help='repetitions of the ladder (seeds 1, 2, ...)')
    p.add_argument('--quick', action='store_true', help='64x64, ladder 16,64, reference 1024 spp')
    p.add_argument('--glint', default=os.path.join(ROOT, 'build', 'examples', 'glint-render'))
    p.add_argument('--glint-args', default='', help='extra glint-render flags for the ladder (not the reference)')
    p.add_argument('--blender', default=shutil.which('blender') or '')
    p.add_argument('--bunny', default=os.path.join(ROOT, '..', 'shared', 'scenes', 'bunny.obj'))
    p.add_argument('--core', type=int, default=1, help='CPU core every render is pinned to')
    p.add_argument('--work', default=os.path.join(ROOT, 'build', 'peer_cycles'), help='renders and cached references')
    p.add_argument('--json', help='write the results here')
    p.add_argument('--markdown', help='print the tables of a --json file as Markdown and exit')
    p.add_argument('--gltf-check', action='store_true',
                   help='instead of the timing: Blender exports each scene as glTF, glint renders it and the '
                        'built-in scene, and the image means are compared (Lambertian and mirror scenes)')
    a = p.parse_args()
    if a.markdown:
        markdown(json.load(open(a.markdown)))
        return 0
    if np is None:
        print('peer_cycles: skipped: numpy is not installed (Debian: apt-get install python3-numpy)')
        return 0
    if not a.blender or not os.path.exists(a.blender):
        print('peer_cycles: skipped: Blender is not installed (Debian: apt-get install blender)')
        return 0
    if not os.path.exists(a.glint):
        sys.exit('peer_cycles: %s not found: build it (cmake --build build --target glint-render)' % a.glint)
    if a.quick:
        a.size, a.ladder, a.ref_spp = 64, '16,64', 1024
    a.ladder = [int(s) for s in a.ladder.split(',')]
    scenes = a.scenes.split(',')
    for s in scenes:
        if s not in SCENES:
            sys.exit('peer_cycles: unknown scene %r (known: %s)' % (s, ', '.join(SCENES)))
    if 'cornell-bunny' in scenes and not os.path.exists(a.bunny):
        print('peer_cycles: cornell-bunny skipped: %s not found (--bunny FILE)' % a.bunny)
        scenes.remove('cornell-bunny')
    rn = Runner(a)
    if a.gltf_check:
        worst = max(gltf_check(rn, a, s) for s in scenes)
        return 0 if worst < 4 else 1
    print('glint-render %s (extra flags: %r) against %s, one thread, pinned to core %d'
          % (a.glint, a.glint_args, run([a.blender, '--version']).splitlines()[0], a.core), flush=True)
    results = [comparison(rn, a, s) for s in scenes]
    if a.json:
        json.dump(results, open(a.json, 'w'), indent=1)
    return 0


if __name__ == '__main__':
    if '--job' in sys.argv:
        blender_main(sys.argv[sys.argv.index('--') + 1:])
    else:
        sys.exit(main())
