#!/usr/bin/python3
"""Where Open3D's ICP variants converge for one Stanford bunny sweep pair, started on the published placement.

Run with /usr/bin/python3 (the interpreter that has Open3D). For the pair FIXED <- MOVING of
/work/shared/datasets/stanford_bunny (metres, read as mm; normals of each scan from its 12 nearest points),
starts point-to-plane, generalized (Segal et al. 2009) and point-to-point ICP on the published placement of
bun.conf (T = P_fixed^-1 P_moving) with gates of 1, 2 and 5 mm, and point-to-plane on a normal-space sample
of the moving scan (Rusinkiewicz and Levoy 2001: 72 buckets of normal direction, sign ignored, the same
number of points from each), and prints one JSON object: for each, the RMS over the moving scan's points of
the distance between the converged and the published placement (mm). If every variant leaves the published
placement by the same amount, the published placement is not the pair's optimum. Used for
docs/benchmarks/registration.md (bun180 <- bun270); registration_benchmark --bunny measures the same for
PCL, Open3D and pectus from the benchmark's own starts.

  /usr/bin/python3 scripts/peers/open3d_bunny_pair.py bun180.ply bun270.ply
"""
import argparse
import json
import os
import sys

import numpy as np
import open3d as o3d

DATA = "/work/shared/datasets/stanford_bunny"


def quaternion_matrix(x, y, z, w):
    q = np.array([x, y, z, w]) / np.linalg.norm([x, y, z, w])
    x, y, z, w = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def read_conf(path):
    """bun.conf poses T_common_scan (mm): x_common = R(q)^T x + t, as pectus's ReadStanfordConf."""
    poses = {}
    for line in open(path):
        v = line.split()
        if v and v[0] == "bmesh":
            x = list(map(float, v[2:]))
            T = np.eye(4)
            T[:3, :3] = quaternion_matrix(*x[3:7]).T
            T[:3, 3] = np.array(x[:3]) * 1000.0
            poses[v[1]] = T
    return poses


def load(name):
    cloud = o3d.io.read_point_cloud(os.path.join(DATA, name))
    cloud.points = o3d.utility.Vector3dVector(np.asarray(cloud.points) * 1000.0)
    cloud.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(12))
    return cloud


def normal_space_sample(cloud, total, seed=0):
    n = np.asarray(cloud.normals).copy()
    n[n[:, 2] < 0] *= -1
    theta = np.arccos(np.clip(n[:, 2], -1, 1))
    phi = np.arctan2(n[:, 1], n[:, 0])
    key = np.minimum((theta / (np.pi / 2) * 6).astype(int), 5) * 12 + \
        ((phi + np.pi) / (2 * np.pi) * 12).astype(int) % 12
    rng = np.random.default_rng(seed)
    buckets = [np.flatnonzero(key == k) for k in np.unique(key)]
    per = total // len(buckets)
    rows = np.concatenate([rng.choice(b, min(per, len(b)), replace=False) for b in buckets])
    return cloud.select_by_index(np.sort(rows).tolist())


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("fixed")
    parser.add_argument("moving")
    args = parser.parse_args()
    poses = read_conf(os.path.join(DATA, "bun.conf"))
    fixed, moving = load(args.fixed), load(args.moving)
    published = np.linalg.inv(poses[args.fixed]) @ poses[args.moving]
    x = np.asarray(moving.points)

    def rms_to_published(T):
        a = x @ T[:3, :3].T + T[:3, 3]
        b = x @ published[:3, :3].T + published[:3, 3]
        return float(np.sqrt(((a - b) ** 2).sum(1).mean()))

    reg = o3d.pipelines.registration
    criteria = reg.ICPConvergenceCriteria(1e-9, 1e-9, 200)
    methods = {"point_to_plane": lambda s, g: reg.registration_icp(
                   s, fixed, g, published, reg.TransformationEstimationPointToPlane(), criteria),
               "generalized": lambda s, g: reg.registration_generalized_icp(
                   s, fixed, g, published, reg.TransformationEstimationForGeneralizedICP(), criteria),
               "point_to_point": lambda s, g: reg.registration_icp(
                   s, fixed, g, published, reg.TransformationEstimationPointToPoint(), criteria)}
    out = {"pair": f"{args.fixed} <- {args.moving}", "open3d_version": o3d.__version__,
           "figure": "RMS distance between the converged and the published placement (mm)"}
    for name, run in methods.items():
        for gate in (1.0, 2.0, 5.0):
            out[f"{name}_gate_{gate:g}mm"] = rms_to_published(run(moving, gate).transformation)
    for total in (5000, 15000):
        sample = normal_space_sample(moving, total)
        for gate in (1.0, 2.0):
            out[f"normal_space_sample_{total}_point_to_plane_gate_{gate:g}mm"] = \
                rms_to_published(methods["point_to_plane"](sample, gate).transformation)
    print(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
