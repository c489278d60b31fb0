#!/usr/bin/python3
"""Open3D multiway registration of N sweeps, for pectus's merge grid benchmark.

Run with /usr/bin/python3 (the interpreter that has Open3D). Follows Open3D's multiway registration
(docs: "Multiway registration"): every sweep is voxel-downsampled (--voxel mm) and gets normals from its
own neighbourhood (estimate_normals, hybrid radius 3 voxels / 30 neighbours); each pair (i, j), i < j, is
aligned by point-to-plane ICP (registration_icp, TransformationEstimationPointToPlane) twice, with a
coarse gate (--coarse mm) then a fine one (--fine mm), from the start poses; a pair whose fine ICP finds
fewer than --min-fitness of the source's points within the gate (no overlap) is left out; the information
matrix of each kept pair (get_information_matrix_from_point_clouds) weights its edge (j = i + 1: odometry;
others: loop closures, uncertain) in a pose graph whose nodes start at the given poses; then
global_optimization (Levenberg-Marquardt, edge_prune_threshold 0.25, reference node 0). Prints one JSON
object: T_world_sweep per sweep (4x4, row-major, mm), the seconds spent after reading (downsampling,
normals, pairwise ICP and the optimisation), the number of edges kept and pruned.

  /usr/bin/python3 scripts/peers/open3d_multiway.py sweep_00.ply sweep_01.ply ... [--init poses.json]
      [--voxel 2] [--coarse 20] [--fine 3]

--init holds {"T_world_sweep": [4x4, ...]}; without it every sweep starts at the identity (its points are
already where the tracker placed them).
"""
import argparse
import json
import sys
import time

import numpy as np
import open3d as o3d


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sweeps", nargs="+")
    parser.add_argument("--init", help="JSON with T_world_sweep: a 4x4 per sweep (mm)")
    parser.add_argument("--voxel", type=float, default=2.0, help="downsampling voxel (mm)")
    parser.add_argument("--coarse", type=float, default=20.0, help="gate of the coarse ICP (mm)")
    parser.add_argument("--fine", type=float, default=3.0, help="gate of the fine ICP and the graph (mm)")
    parser.add_argument("--min-fitness", type=float, default=0.05, help="pairs below are not linked")
    args = parser.parse_args()
    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)

    clouds = [o3d.io.read_point_cloud(path) for path in args.sweeps]
    n = len(clouds)
    init = [np.identity(4) for _ in range(n)]
    if args.init:
        with open(args.init) as f:
            init = [np.array(T, dtype=np.float64) for T in json.load(f)["T_world_sweep"]]

    start = time.perf_counter()
    down = []
    for c in clouds:
        d = c.voxel_down_sample(args.voxel)
        d.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=3 * args.voxel, max_nn=30))
        down.append(d)
    reg = o3d.pipelines.registration
    graph = reg.PoseGraph()
    for i in range(n):
        graph.nodes.append(reg.PoseGraphNode(init[i]))
    edges = 0
    for i in range(n):
        for j in range(i + 1, n):
            # T_i_j: sweep j's frame to sweep i's, starting from the given poses.
            T = np.linalg.inv(init[i]) @ init[j]
            coarse = reg.registration_icp(down[j], down[i], args.coarse, T,
                                          reg.TransformationEstimationPointToPlane())
            fine = reg.registration_icp(down[j], down[i], args.fine, coarse.transformation,
                                        reg.TransformationEstimationPointToPlane())
            if fine.fitness < args.min_fitness:
                continue
            info = reg.get_information_matrix_from_point_clouds(down[j], down[i], args.fine,
                                                                 fine.transformation)
            # An edge (source j, target i) holds T_i_j, as in the tutorial (x_target = T x_source).
            graph.edges.append(reg.PoseGraphEdge(j, i, fine.transformation, info, uncertain=(j != i + 1)))
            edges += 1
    option = reg.GlobalOptimizationOption(max_correspondence_distance=args.fine, edge_prune_threshold=0.25,
                                          reference_node=0)
    reg.global_optimization(graph, reg.GlobalOptimizationLevenbergMarquardt(),
                            reg.GlobalOptimizationConvergenceCriteria(), option)
    seconds = time.perf_counter() - start
    print(json.dumps({
        "method": "open3d multiway registration (pairwise point-to-plane ICP + global_optimization)",
        "open3d_version": o3d.__version__,
        "T_world_sweep": [np.asarray(node.pose).tolist() for node in graph.nodes],
        "seconds": seconds,
        "edges_kept": len(graph.edges),
        "edges_linked": edges,
        "voxel_mm": args.voxel, "coarse_mm": args.coarse, "fine_mm": args.fine,
    }))
    return 0


if __name__ == "__main__":
    sys.exit(main())
