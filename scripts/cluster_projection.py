#!/usr/bin/env python3
"""Projects `pectus pipeline` on P MPI ranks from one measured run (docs/cluster.md, docs/benchmarks.md).

Input: the --report JSON of a run with one thread (`pectus pipeline C --out O --threads 1 --report r.json`):
each subject's stage times (s) and the run's own stages. The model of a run on P ranks of one thread each:

  T(P) = A(P) + B(P) + S(N)
  A(P), B(P)  the makespans of the two farmed phases: subjects' surfaces (read, merge, reconstruct), then
              their registration and grid (register, resample, measures), each task handed to the first
              free rank in the order given (largest first, or the subjects' order), a rank waiting for the
              last task of phase A before phase B (the reference must be known);
  S(N)        rank 0 alone: the model (Procrustes, imputation, PCA: taken as growing with N^2, the Gram
              matrix), the distance maps and the outputs (with N), measured on this run.
  efficiency  T(1) / (P T(P)).
--farm-only leaves S out: how the farm itself scales.

A cohort larger than the measured one draws its subjects' times from the measured ones (fixed seed).
"""
import argparse
import heapq
import json
import random


def makespan(times, ranks):
    free = [0.0] * ranks
    for t in times:
        heapq.heapreplace(free, free[0] + t)
    return max(free)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("report", help="pipeline --report JSON of a one-thread run")
    ap.add_argument("--subjects", type=int, nargs="+", default=[200, 2000])
    ap.add_argument("--ranks", type=int, nargs="+", default=[1, 2, 8, 16, 32, 64])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--farm-only", action="store_true", help="leave rank 0's own part out (S = 0)")
    a = ap.parse_args()
    r = json.load(open(a.report))
    subjects = [s for s in r["subjects"]]
    phase_a = [sum(s["timings_s"].get(k, 0.0) for k in ("read", "merge", "reconstruct")) for s in subjects]
    phase_b = [sum(s["timings_s"].get(k, 0.0) for k in ("register", "resample", "measures")) for s in subjects]
    n0 = len(subjects)
    total = r["timings_s"]
    farmed = sum(phase_a) + sum(phase_b)
    model = sum(total.get(k, 0.0) for k in ("model", "quality"))
    linear = total.get("distance", 0.0) + total.get("write", 0.0)
    wall = sum(r["timings_s"].get(k, 0.0) for k in ("pipeline", "write")) if "pipeline" in r["timings_s"] else None
    print(f"measured: {n0} subjects; per subject surface {sum(phase_a)/n0:.3f} s, registration and grid "
          f"{sum(phase_b)/n0:.3f} s (mean); rank 0 alone: model {model:.2f} s, distance + outputs {linear:.2f} s")
    rng = random.Random(a.seed)
    for n in a.subjects:
        if n == n0:
            ta, tb = phase_a, phase_b
        else:
            draw = [rng.randrange(n0) for _ in range(n)]
            ta, tb = [phase_a[i] for i in draw], [phase_b[i] for i in draw]
        serial = 0.0 if a.farm_only else model * (n / n0) ** 2 + linear * (n / n0)
        t1 = sum(ta) + sum(tb) + serial
        for p in a.ranks:
            for order, name in ((sorted, "largest first"), (list, "subject order")):
                oa = sorted(ta, reverse=True) if order is sorted else ta
                ob = sorted(tb, reverse=True) if order is sorted else tb
                tp = makespan(oa, p) + makespan(ob, p) + serial
                print(f"N={n:5d} P={p:3d} {name:14s} T={tp:9.1f} s  speed-up {t1/tp:6.2f}  "
                      f"efficiency {100*t1/(p*tp):5.1f} %  (rank 0 alone {serial:.1f} s)")


if __name__ == "__main__":
    main()
