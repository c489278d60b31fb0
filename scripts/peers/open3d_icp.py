#!/usr/bin/python3
"""Open3D point-to-plane (or generalized) ICP on two point clouds, for pectus's registration benchmark.

Run with /usr/bin/python3 (the interpreter that has Open3D). Reads the target and source PLY files (with
normals: the benchmark gives every method the same precomputed normals), the initial 4x4 pose from a JSON
file {"T_target_source": [[...] x4]}, runs o3d.pipelines.registration.registration_icp with
TransformationEstimationPointToPlane (or, with --method generalized, registration_generalized_icp: Segal et
al. 2009, covariances from each cloud's own neighbourhoods) once per stage, and prints one JSON object: the transform, the seconds
spent in registration_icp alone (file reading and sampling excluded; Open3D builds its target k-d tree
inside every call, so that is included, as it is for pectus), the CPU seconds of the process over the same
span (all threads), fitness and inlier RMSE.

A stage is GATE_MM:POINTS (POINTS = 0: every source point; otherwise a random subset of that many, drawn
once before timing, nested like pectus's levels). One stage with a single gate is plain ICP.

  /usr/bin/python3 scripts/peers/open3d_icp.py target.ply source.ply init.json \\
      --stages 15:0 --max-iterations 50 --repeat 3
  /usr/bin/python3 scripts/peers/open3d_icp.py target.ply source.ply init.json \\
      --stages 15:0 --transform-out T.json > /dev/null   # as a whole process (registration_benchmark --process)
  /usr/bin/python3 scripts/peers/open3d_icp.py target.ply source.ply init.json \\
      --stages 20:1000,5:3000,2.7:10000,2.7:0 --max-iterations 30
"""
import argparse
import json
import os
import sys
import time

import numpy as np
import open3d as o3d


def parse_stages(text):
    stages = []
    for item in text.split(","):
        gate, points = item.split(":")
        stages.append((float(gate), int(points)))
    return stages


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("target")
    parser.add_argument("source")
    parser.add_argument("init", help="JSON with T_target_source (4x4, row-major, mm)")
    parser.add_argument("--stages", default="15:0", help="GATE_MM:POINTS,... coarse to fine")
    parser.add_argument("--max-iterations", type=int, default=50, help="per stage")
    parser.add_argument("--relative-fitness", type=float, default=1e-6)
    parser.add_argument("--relative-rmse", type=float, default=1e-6)
    parser.add_argument("--method", default="point-to-plane", choices=["point-to-plane", "generalized"])
    parser.add_argument("--repeat", type=int, default=1, help="runs; the median and best are reported")
    parser.add_argument("--transform-out", help="also write {\"T_target_source\": 4x4} to this JSON file")
    args = parser.parse_args()

    target = o3d.io.read_point_cloud(args.target)
    source = o3d.io.read_point_cloud(args.source)
    if not target.has_normals():
        print(json.dumps({"error": f"{args.target} has no normals"}))
        return 3
    with open(args.init) as f:
        init = np.array(json.load(f)["T_target_source"], dtype=np.float64)
    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)

    # Nested random subsets, drawn once (not timed).
    stages = parse_stages(args.stages)
    order = np.random.default_rng(1).permutation(len(source.points))
    sources = [source if n <= 0 or n >= len(order) else source.select_by_index(np.sort(order[:n]).tolist())
               for _, n in stages]

    times, cpu = [], []
    result = None
    for _ in range(max(1, args.repeat)):
        T = init
        start = time.perf_counter()
        cpu_start = time.process_time()
        for (gate, _), src in zip(stages, sources):
            criteria = o3d.pipelines.registration.ICPConvergenceCriteria(
                relative_fitness=args.relative_fitness, relative_rmse=args.relative_rmse,
                max_iteration=args.max_iterations)
            if args.method == "generalized":
                result = o3d.pipelines.registration.registration_generalized_icp(
                    src, target, gate, T,
                    o3d.pipelines.registration.TransformationEstimationForGeneralizedICP(), criteria)
            else:
                result = o3d.pipelines.registration.registration_icp(
                    src, target, gate, T,
                    o3d.pipelines.registration.TransformationEstimationPointToPlane(), criteria)
            T = result.transformation
        times.append(time.perf_counter() - start)
        cpu.append(time.process_time() - cpu_start)

    if args.transform_out:
        with open(args.transform_out, "w") as f:
            json.dump({"T_target_source": np.asarray(result.transformation).tolist()}, f)
    print(json.dumps({
        "method": ("registration_generalized_icp" if args.method == "generalized"
                   else "registration_icp point-to-plane"),
        "open3d_version": o3d.__version__,
        "stages": args.stages,
        "T_target_source": np.asarray(result.transformation).tolist(),
        "seconds_median": float(np.median(times)),
        "seconds_best": float(np.min(times)),
        "cpu_seconds_median": float(np.median(cpu)),
        "threads": int(os.environ.get("OMP_NUM_THREADS", os.cpu_count())),
        "fitness": result.fitness,
        "inlier_rmse_mm": result.inlier_rmse,
        "source_points": len(source.points),
        "target_points": len(target.points),
    }))
    return 0


if __name__ == "__main__":
    sys.exit(main())
