#!/usr/bin/python3
"""Open3D screened Poisson surface reconstruction of a point cloud, for pectus's reconstruction benchmark.

Run with /usr/bin/python3 (the interpreter that has Open3D). Reads a PLY cloud (mm), uses its normals or,
with --estimate-normals, estimates them (KNN) and orients them consistently (tangent-plane propagation), as
a user of Open3D alone would; runs o3d.geometry.TriangleMesh.create_from_point_cloud_poisson at the given
octree depth, optionally removes the vertices of lowest density (--density-quantile, the documented way to
cut away Poisson's surface far from the data), writes the mesh as PLY and prints one JSON object with the
seconds of each stage (file reading and writing excluded), the counts, and the peak resident memory of this
process (MB).

  /usr/bin/python3 scripts/peers/open3d_poisson.py cloud.ply surface.ply --depth 8
  /usr/bin/python3 scripts/peers/open3d_poisson.py cloud.ply surface.ply --depth 8 --estimate-normals
  /usr/bin/python3 scripts/peers/open3d_poisson.py cloud.ply surface.ply --depth 8 --threads 1
"""
import argparse
import json
import os
import resource
import sys
import time

import numpy as np


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cloud")
    parser.add_argument("output")
    parser.add_argument("--depth", type=int, default=8)
    parser.add_argument("--estimate-normals", action="store_true")
    parser.add_argument("--neighbours", type=int, default=16)
    parser.add_argument("--density-quantile", type=float, default=0.0)
    parser.add_argument("--threads", type=int, default=0,
                        help="run on this many cores (the process is pinned to them); 0 = all")
    args = parser.parse_args()
    if args.threads > 0:
        # Open3D sizes its thread pools from the cores it may use, whatever OMP_NUM_THREADS says.
        cores = sorted(os.sched_getaffinity(0))
        os.sched_setaffinity(0, cores[:args.threads])
    # Imported after pinning: its OpenMP runtime sizes its thread pool when it loads.
    import open3d as o3d  # pylint: disable=import-outside-toplevel

    pcd = o3d.io.read_point_cloud(args.cloud)
    if len(pcd.points) == 0:
        print(json.dumps({"error": f"{args.cloud}: no points"}))
        return 3
    seconds = {}
    cpu0 = time.process_time()
    if args.estimate_normals or not pcd.has_normals():
        t = time.perf_counter()
        pcd.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(args.neighbours))
        seconds["normals"] = time.perf_counter() - t
        t = time.perf_counter()
        pcd.orient_normals_consistent_tangent_plane(args.neighbours)
        seconds["orientation"] = time.perf_counter() - t
    t = time.perf_counter()
    mesh, densities = o3d.geometry.TriangleMesh.create_from_point_cloud_poisson(pcd, depth=args.depth)
    seconds["poisson"] = time.perf_counter() - t
    if args.density_quantile > 0:
        t = time.perf_counter()
        densities = np.asarray(densities)
        mesh.remove_vertices_by_mask(densities < np.quantile(densities, args.density_quantile))
        seconds["trim"] = time.perf_counter() - t
    cpu_s = time.process_time() - cpu0  # CPU time of this process, all threads, file reading excluded
    o3d.io.write_triangle_mesh(args.output, mesh)
    print(json.dumps({
        "seconds": seconds,
        "total_s": sum(seconds.values()),
        "surface_cpu_s": cpu_s,
        "points": len(pcd.points),
        "vertices": len(mesh.vertices),
        "faces": len(mesh.triangles),
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
        "open3d": o3d.__version__,
    }))
    return 0


if __name__ == "__main__":
    sys.exit(main())
