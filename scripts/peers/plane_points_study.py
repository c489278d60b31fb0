#!/usr/bin/python3
"""Which target plane leaves point-to-plane ICP unbiased on noisy scans (docs/registration.md, "The target's
plane from its nearest points").

Every-point point-to-plane ICP as pectus runs its last level (Cauchy weights on the MAD scale floored at
0.02 mm, the gate 3 point spacings, pairs farther than 2 spacings along the target's tangent plane dropped),
in numpy with Open3D's neighbour search, from a given start, with one residual per mode:

  plain     the nearest target point's own plane (Chen and Medioni 1992)
  avgK      the plane through the mean of the K nearest target points, normal their mean normal
  plain15   no weights, a 15 mm gate, no tangential test (Open3D's documented use)

Input: a folder the registration benchmark keeps (`PECTUS_PROCESS_DIR=DIR registration_benchmark --process`):
fixed.ply and moving.ply (binary, with normals), truth.json and a start pose (pectus.json by default).
Prints the RMS over the moving points of the distance between the result's placement and the truth's.
With SUB=n (environment) only a random n of the moving points are used (SEED=s picks them).

    /usr/bin/python3 scripts/peers/plane_points_study.py DIR/seed1004 plain,avg2,avg3,avg4,avg6 pectus.json
"""
import json
import os
import sys

import numpy as np
import open3d as o3d


def read_ply(path):
    with open(path, 'rb') as f:
        n = props = 0
        while True:
            line = f.readline().decode().strip()
            if line.startswith('element vertex'):
                n = int(line.split()[2])
            if line.startswith('property'):
                props += 1
            if line == 'end_header':
                break
        a = np.frombuffer(f.read(n * props * 4), dtype='<f4').reshape(n, props).astype(float)
    return a[:, :3], a[:, 3:6]


def read_pose(path):
    return np.array(json.load(open(path))['T_target_source'])


def rotation(w):
    theta = np.linalg.norm(w)
    if theta < 1e-15:
        return np.eye(3)
    k = w / theta
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(theta) * K + (1 - np.cos(theta)) * K @ K


def main():
    folder, modes = sys.argv[1], sys.argv[2].split(',')
    start = read_pose(os.path.join(folder, sys.argv[3] if len(sys.argv) > 3 else 'pectus.json'))
    truth = read_pose(os.path.join(folder, 'truth.json'))
    F, FN = read_ply(os.path.join(folder, 'fixed.ply'))
    M, _ = read_ply(os.path.join(folder, 'moving.ply'))
    every = M.copy()
    sub = int(os.environ.get('SUB', '0'))
    if sub:
        rng = np.random.default_rng(int(os.environ.get('SEED', '1')))
        M = M[np.sort(rng.choice(len(M), sub, replace=False))]
    c0 = F.mean(0)
    Fc = F - c0
    nns = o3d.core.nns.NearestNeighborSearch(o3d.core.Tensor(Fc))
    nns.knn_index()
    _, d2 = nns.knn_search(o3d.core.Tensor(Fc[::400].copy()), 2)
    spacing = np.median(np.sqrt(d2.numpy()[:, 1]))
    gate = 3 * spacing
    C = np.eye(4)
    C[:3, 3] = c0
    for mode in modes:
        T = start.copy()
        for it in range(30):
            P = M @ T[:3, :3].T + T[:3, 3] - c0
            idx, d2 = nns.knn_search(o3d.core.Tensor(P), 8)
            idx, d2 = idx.numpy(), d2.numpy()
            j = idx[:, 0]
            q, n = Fc[j], FN[j].copy()
            if mode.startswith('avg'):
                k = int(mode[3:])
                nk = FN[idx[:, :k]]
                nk = nk * np.sign(np.einsum('ijk,ik->ij', nk, n))[:, :, None]
                n = nk.sum(1)
                n /= np.linalg.norm(n, axis=1)[:, None]
                q = Fc[idx[:, :k]].mean(1)
            d = P - Fc[j]
            along = np.einsum('ij,ij->i', d, FN[j])
            if mode == 'plain15':
                ok = d2[:, 0] <= 15 * 15
            else:
                ok = (d2[:, 0] <= gate * gate) & ((d * d).sum(1) - along ** 2 <= (2 * spacing) ** 2)
            p, q, n = P[ok], q[ok], n[ok]
            r = np.einsum('ij,ij->i', p - q, n)
            if mode == 'plain15':
                w = np.ones_like(r)
            else:
                c = 2.3849 * max(1.4826 * np.median(np.abs(r)), 0.02)
                w = 1 / (1 + (r / c) ** 2)
            pc = p.mean(0)
            J = np.hstack([np.cross(p - pc, n), n])
            x = -np.linalg.solve((J * w[:, None]).T @ J, (J * w[:, None]).T @ r)
            R = rotation(x[:3])
            dT = np.eye(4)
            dT[:3, :3] = R
            dT[:3, 3] = x[3:] + pc - R @ pc
            T = C @ dT @ np.linalg.inv(C) @ T
            if np.linalg.norm(x) < 1e-7:
                break
        diff = (every @ T[:3, :3].T + T[:3, 3]) - (every @ truth[:3, :3].T + truth[:3, 3])
        print('%s %-8s iterations %2d  rms %.4f mm' % (os.path.basename(folder.rstrip('/')), mode, it + 1,
                                                       np.sqrt((diff ** 2).sum(1).mean())), flush=True)


if __name__ == '__main__':
    main()
