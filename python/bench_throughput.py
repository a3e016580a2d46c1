"""Rays per second of glint.MeshBvh's batch calls (threads=1) against MeshBvh's own C++ loop
(glint_python_hits) on the same mesh and the same 10^6 rays, alternating, pinned to one core.

    PYTHONPATH=build/python python3 python/bench_throughput.py [--rays N] [--rounds R] [--cpu C] [--mesh FILE.obj]

Both sides measure their thread's CPU time (threads=1 traces on the calling thread), so that
other work on a shared core is left out. Mesh: ../shared/scenes/bunny.obj beside the repository (or $GLINT_SCENES/bunny.obj), else a
generated bumpy sphere of 40000 triangles. Prints the median seconds of each side and the
throughput ratio Python / C++ (1 = as fast as the C++ loop; the Python call also writes its
arrays and computes each hit's normal; the closest-no-normals row calls it with normals=False)."""
import argparse
import os
import pathlib
import statistics
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).parent / "tests"))
import glint  # noqa: E402
from hits_io import comparison_mesh, cpp_hits, random_rays  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rays", type=int, default=10**6)
    ap.add_argument("--rounds", type=int, default=9)
    ap.add_argument("--cpu", type=int, default=0, help="the core both sides run on (default 0)")
    ap.add_argument("--mesh", help="an OBJ file instead of the bunny")
    a = ap.parse_args()
    os.sched_setaffinity(0, {a.cpu})  # the C++ side's process inherits it
    if a.mesh:
        m = glint.load_obj(a.mesh)
        vertices, indices, mesh_name = m["vertices"], m["indices"], pathlib.Path(a.mesh).name
    else:
        vertices, indices, mesh_name = comparison_mesh()
    origins, directions = random_rays(vertices, a.rays)
    bvh = glint.MeshBvh(vertices, indices)
    times = {k: [] for k in ("cpp closest", "py closest", "py closest-no-normals", "cpp any", "py any")}
    for r in range(a.rounds):
        for side in (("cpp", "py") if r % 2 == 0 else ("py", "cpp")):
            if side == "cpp":
                _, closest, anyhit = cpp_hits(vertices, indices, origins, directions)
                times["cpp closest"].append(closest)
                times["cpp any"].append(anyhit)
                continue
            for name, call in (("closest", lambda: bvh.closest_hit(origins, directions, threads=1)),
                               ("closest-no-normals", lambda: bvh.closest_hit(origins, directions, threads=1, normals=False)),
                               ("any", lambda: bvh.any_hit(origins, directions, threads=1))):
                start = time.thread_time()
                call()
                times["py " + name].append(time.thread_time() - start)
    med = {k: statistics.median(v) for k, v in times.items()}
    print(f"mesh {mesh_name}: {len(indices)} triangles, {a.rays} rays, {a.rounds} alternating rounds on core {a.cpu} "
          f"(median thread CPU seconds), "
          f"glint {glint.__version__}, kernels {bvh.isa}")
    for q in ("closest", "closest-no-normals", "any"):
        c, p = med["cpp " + q.split("-")[0]], med["py " + q]
        print(f"{q + ' hit':22s}: C++ loop {c:.4f} s ({a.rays / c * 1e-6:.2f} Mrays/s), Python batch {p:.4f} s "
              f"({a.rays / p * 1e-6:.2f} Mrays/s): Python / C++ throughput {c / p:.3f}")


if __name__ == "__main__":
    main()
