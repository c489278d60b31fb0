#!/usr/bin/python3
"""Open3D point-to-plane ICP on two point clouds, for pectus's registration benchmark.

Run with /usr/bin/python3 (the interpreter that has Open3D). Reads the target and source PLY files (with
normals: the benchmark gives every method the same precomputed normals), the initial 4x4 pose from a JSON
file {"T_target_source": [[...] x4]}, runs o3d.pipelines.registration.registration_icp with
TransformationEstimationPointToPlane, and prints one JSON object: the transform, the seconds spent in
registration_icp alone (file reading excluded, best of --repeat runs), fitness and inlier RMSE.

  /usr/bin/python3 scripts/peers/open3d_icp.py target.ply source.ply init.json \
      --max-distance 15 --max-iterations 50 --repeat 3
"""
import argparse
import json
import sys
import time

import numpy as np
import open3d as o3d


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("target")
    parser.add_argument("source")
    parser.add_argument("init", help="JSON with T_target_source (4x4, row-major, mm)")
    parser.add_argument("--max-distance", type=float, default=15.0, help="correspondence gate, mm")
    parser.add_argument("--max-iterations", type=int, default=50)
    parser.add_argument("--relative-fitness", type=float, default=1e-6)
    parser.add_argument("--relative-rmse", type=float, default=1e-6)
    parser.add_argument("--voxel", type=float, default=0.0,
                        help="voxel-downsample the source first (mm); 0 = use every point")
    parser.add_argument("--repeat", type=int, default=1, help="runs; the fastest is reported")
    args = parser.parse_args()

    target = o3d.io.read_point_cloud(args.target)
    source = o3d.io.read_point_cloud(args.source)
    if not target.has_normals():
        print(json.dumps({"error": f"{args.target} has no normals"}))
        return 3
    with open(args.init) as f:
        init = np.array(json.load(f)["T_target_source"], dtype=np.float64)
    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)

    best = None
    result = None
    for _ in range(max(1, args.repeat)):
        start = time.perf_counter()
        src = source.voxel_down_sample(args.voxel) if args.voxel > 0 else source
        result = o3d.pipelines.registration.registration_icp(
            src, target, args.max_distance, init,
            o3d.pipelines.registration.TransformationEstimationPointToPlane(),
            o3d.pipelines.registration.ICPConvergenceCriteria(
                relative_fitness=args.relative_fitness, relative_rmse=args.relative_rmse,
                max_iteration=args.max_iterations))
        seconds = time.perf_counter() - start
        best = seconds if best is None else min(best, seconds)

    print(json.dumps({
        "method": "open3d registration_icp point-to-plane",
        "open3d_version": o3d.__version__,
        "T_target_source": np.asarray(result.transformation).tolist(),
        "seconds": best,
        "fitness": result.fitness,
        "inlier_rmse_mm": result.inlier_rmse,
        "source_points": len(source.points),
        "target_points": len(target.points),
    }))
    return 0


if __name__ == "__main__":
    sys.exit(main())
