#!/usr/bin/python3
"""numpy's routes to a shape model's PCA, for pectus's model benchmark (model_benchmark pca).

Run with /usr/bin/python3 (Debian's numpy). Reads N shape vectors of D numbers each, not centred (float64,
an N x D matrix written by Eigen in its column-major order: number 1 of every shape, then number 2, ...),
and times each route from the same uncentred matrix (the centring is inside every time, as it is inside
pectus's BuildShapeModel):

  svd        thin SVD of the centred N x D matrix X (np.linalg.svd, full_matrices=False): the modes are
             the right singular vectors, the variances s^2 / (N - 1)
  gram_eigh  pectus's route: G = X X' (N x N), np.linalg.eigh(G), the modes X' v / s of the modes above
             the relative tolerance, and the training scores X e (the same steps as BuildShapeModel)

Prints one JSON object: wall seconds per route (median and best of --repeat runs) and CPU seconds of the
process (all threads, median), the first 20 variances of
each route, the largest relative difference between the two routes' first 20 variances, the BLAS and
LAPACK libraries numpy runs on (from /proc/self/maps) and the thread variables it was given.

  /usr/bin/python3 scripts/peers/numpy_pca.py shapes.f64 N D [--repeat 1]
"""
import argparse
import json
import os
import sys
import time

import numpy as np


def svd_route(shapes):
    x = shapes - shapes.mean(axis=0)
    _, s, vt = np.linalg.svd(x, full_matrices=False)
    return s * s / (len(shapes) - 1), vt


def gram_route(shapes, relative_tolerance=1e-10):  # ShapeModelOptions default
    x = shapes - shapes.mean(axis=0)
    g = x @ x.T
    w, v = np.linalg.eigh(g)
    w, v = w[::-1], v[:, ::-1]
    k = int(np.count_nonzero(w > relative_tolerance * max(w[0], 0.0)))
    k = min(k, len(shapes) - 1)
    basis = (x.T @ v[:, :k]) / np.sqrt(w[:k])
    scores = x @ basis
    return w[:k] / (len(shapes) - 1), basis, scores


def linked_libraries():
    names = set()
    try:
        with open("/proc/self/maps") as maps:
            for line in maps:
                path = line.split()[-1]
                base = os.path.basename(path)
                if any(key in base for key in ("blas", "lapack", "atlas", "mkl")):
                    names.add(os.path.realpath(path))
    except OSError:
        pass
    return sorted(names)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("shapes", help="float64, D x N column-major from Eigen (N shapes of D numbers)")
    parser.add_argument("n", type=int, help="number of shapes N")
    parser.add_argument("d", type=int, help="numbers per shape D")
    parser.add_argument("--repeat", type=int, default=1, help="runs per route; median and best reported")
    args = parser.parse_args()

    # Eigen writes its N x D matrix column by column: D rows of N numbers read as a (D, N) array.
    shapes = np.ascontiguousarray(np.fromfile(args.shapes, dtype=np.float64).reshape(args.d, args.n).T)
    out = {"numpy_version": np.__version__, "subjects": args.n, "numbers_per_shape": args.d,
           "blas_lapack_libraries": linked_libraries(),
           "thread_variables": {k: os.environ[k] for k in
                                ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
                                if k in os.environ},
           "routes": {}}
    variances = {}
    for name, route in (("svd", svd_route), ("gram_eigh", gram_route)):
        times, cpu = [], []
        for _ in range(max(1, args.repeat)):
            start, cpu_start = time.perf_counter(), time.process_time()
            result = route(shapes)
            times.append(time.perf_counter() - start)
            cpu.append(time.process_time() - cpu_start)
        variances[name] = result[0][:20]
        out["routes"][name] = {"seconds_median": float(np.median(times)), "seconds_best": float(min(times)),
                               "cpu_seconds_median": float(np.median(cpu)), "runs": len(times),
                               "variances_first_20": variances[name].tolist()}
    k = min(len(variances["svd"]), len(variances["gram_eigh"]))
    out["max_relative_variance_difference_svd_vs_gram_first_20"] = float(
        np.max(np.abs(variances["gram_eigh"][:k] - variances["svd"][:k]) / variances["svd"][:k]))
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
