#!/usr/bin/env python3
"""Projects `pectus pipeline` on P MPI ranks from one measured run (docs/cluster.md, docs/benchmarks.md).

Input: the --report JSON of a run with one thread (`pectus pipeline C --out O --threads 1 --report r.json`):
each subject's stage times (s) and the run's own stages. The model of a run on P ranks of one thread each:

  T(P) = A(P) + B(P) + C(P) + D(P) + S(N)
  A(P) .. D(P) the makespans of the four farmed phases: subjects' surfaces (read, merge, reconstruct), their
              registration and grid (register, resample, measures), their distance to the mean and output
              files (distance, files), their report pictures (the run's "pictures" spread evenly over the
              subjects); each task handed to the first free rank in the order given (largest first, or the
              subjects' order), every rank waiting for the last task of one phase before the next (the
              reference, the model, the colour scale);
  S(N)        rank 0 alone: the model (Procrustes, imputation, PCA: "model", "quality", taken as growing with
              N^2, the Gram matrix) and what grows with N: reading the records back, writing the model's
              per-subject records, the mean's measures, the outputs ("read back", "model records",
              "mean measures", "write"), measured on this run. Before the outputs were farmed, the report
              had "distance" on rank 0 and the subjects' files in "write": those count in S as they ran.
              A report with the model's steps ("model align", "model impute", "model pca": the model as a
              collective, docs/cluster.md) splits the model: the alignment and the eigen decomposition
              (--eig N:SECONDS, measured by `model_benchmark model N`, scaled as N^3) stay on rank 0; the
              imputation (scaled as N) and the rest of the PCA (N^2) are shared: divided by P. A report
              that also has "model read" (the grids read back in blocks shared among the ranks) has the
              alignment ("model align"), the subjects' records ("model records") and that read shared as
              well (scaled as N), with "remove results" (each rank removes a block of the subjects' work
              files); "model shapes" (in reports of 2026-11-28 04:00-04:30 UTC only: every rank aligning
              every grid alike, before that became blocks of vertices too) counts in S.
              A report with "model files" (the model's own files, written by rank 0 in a thread of its own
              while the third tasks run) counts them as one more task of that phase (scaled as N).
              A report with "model eig" (the eigen decomposition on rank 0 in a thread of its own while the
              ranks run the third and fourth tasks, and rank 0 reads the subjects' summaries back beside the
              fourth): rank 0's core decomposes and reads while the other P - 1 ranks run both phases,
              T(P) = A(P) + B(P) + max(EIG + R, C(P - 1) + D(P - 1)) + S(N) + SHARED / P (one rank: EIG +
              C(1) + R + D(1)), EIG scaled as N^3, R ("read back") as N.
              A report with "model outputs" (the files of the model alone, model.h5, its tables and the
              report's figures of it, one task each on the farm after the fourth tasks) adds that phase,
              E(P) = min(E, E / P + (1 - 1 / P) L) (the bound of a greedy hand-out, from the phase's total E
              and its longest task L, "model outputs largest"), both scaled as N.
  efficiency  T(1) / (P T(P)).
--farm-only leaves S out: how the farm itself scales.

--dataset: the report is instead that of `pectus surrogate build` (or `pectus plan --dataset`) run on one
rank of one thread; its patients are the tasks:

  T(P) = S + M(P) + A + R / P
  M(P) the makespan of the patients' tasks, each handed in table order to the first free rank: a task's
       own time ("dataset.per_patient": "seconds" less "setup_seconds"), and on each rank's first task the
       process's setup G as well (the generic ribcage, built once per process: the largest
       "setup_seconds" of the run);
  A    the assembly of the parts on rank 0 ("dataset.assemble_seconds");
  R    removing the parts once the dataset is made ("dataset.remove_parts_seconds"): each rank removes
       the parts it made, at once;
  S    what the run did besides (the plugin, the table, the folders): the run's total less the tasks, A
       and R.
  The issue's line: T(P) within the slowest patient's time plus 10 % when P >= the patients; both the
  slowest task as the P ranks run it (its own time plus G) and its own time alone are shown.

A cohort larger than the measured one draws its subjects' times from the measured ones (fixed seed).
"""
import argparse
import heapq
import json
import random


def makespan(times, ranks, busy=0.0):
    """Tasks handed in order to the first free of `ranks` ranks; rank 0 busy for `busy` seconds first."""
    free = [busy] + [0.0] * (ranks - 1)
    heapq.heapify(free)
    for t in times:
        heapq.heapreplace(free, free[0] + t)
    return max(free)


def dataset(report, ranks):
    r = json.load(open(report))
    d = r["dataset"]
    rows = [p for p in d["per_patient"] if p.get("seconds") is not None]
    setups = [p.get("setup_seconds", 0.0) for p in rows]
    own = [p["seconds"] - g for p, g in zip(rows, setups)]
    setup = max(setups)
    total = r["timings_s"]["total"]
    assemble = d["assemble_seconds"]
    remove = d.get("remove_parts_seconds", 0.0)
    serial = max(0.0, total - sum(p["seconds"] for p in rows) - assemble - remove)
    slowest = max(own)
    print(f"measured: {len(own)} patients, {sum(own):.1f} s of their own tasks (mean {sum(own)/len(own):.2f} s, "
          f"slowest {slowest:.2f} s), setup per process {setup:.2f} s, assembly {assemble:.2f} s, removing "
          f"the parts {remove:.2f} s, the rest of the run {serial:.2f} s, total {total:.1f} s")
    t1 = serial + sum(own) + setup + assemble + remove
    for p in ranks:
        tp = serial + makespan_first(own, p, setup) + assemble + remove / p
        print(f"P={p:3d} T={tp:8.2f} s  speed-up {t1/tp:6.2f}  efficiency {100*t1/(p*tp):5.1f} %  "
              f"T / (slowest + setup) {tp/(slowest + setup):5.3f}  T / slowest {tp/slowest:5.3f}")


def rank0_model(total, n0, eig_n, eig_s, farmed_outputs=True):
    """(rank 0 alone, shared among the ranks) at N subjects, from the run-level stages `total` of a run of n0."""
    linear = sum(total.get(k, 0.0) for k in ("read back", "model records", "mean measures", "write"))
    if not farmed_outputs:  # a run from before the outputs were farmed: its distances ran on rank 0
        linear += total.get("distance", 0.0)
    if "model align" not in total:  # before the model was a collective: all of it on rank 0, as N^2
        model = sum(total.get(k, 0.0) for k in ("model", "quality"))
        return lambda n: (model * (n / n0) ** 2 + linear * (n / n0), 0.0, 0.0, 0.0)
    align, impute, pca = (total.get(k, 0.0) for k in ("model align", "model impute", "model pca"))
    linear_shared = 0.0
    if "model read" in total:  # the grids read, aligned and recorded in blocks shared among the ranks
        linear_shared = sum(total.get(k, 0.0) for k in ("model read", "model records", "remove results")) + align
        linear -= total.get("model records", 0.0)
        align = total.get("model shapes", 0.0)  # every rank did it alike: rank 0's time all the same
    eig_here = eig_s * (n0 / eig_n) ** 3 if eig_s is not None else 0.0
    overlap = "model eig" in total  # the decomposition beside the third and fourth tasks
    if overlap:
        # the run's own decomposition time, or --eig's scaled to this run's N
        eig_s = total["model eig"] if eig_s is None else eig_s * (n0 / eig_n) ** 3
        eig_n, eig_here = n0, total["model eig"]
        linear -= total.get("read back", 0.0)  # in the window, between the third and fourth tasks
        pca += eig_here  # "model pca" is the rest of the PCA, all of it shared

    def parts(n):
        eig = eig_s * (n / eig_n) ** 3 if eig_s is not None else 0.0
        quality = total.get("quality", 0.0) * (n / n0) ** 2
        serial = (align + linear) * (n / n0) + (0.0 if overlap else eig) + quality
        shared = (impute + linear_shared) * (n / n0) + max(0.0, pca - eig_here) * (n / n0) ** 2
        if not overlap:
            return serial, shared, 0.0, 0.0
        return serial, shared, eig, total.get("read back", 0.0) * (n / n0)
    return parts


def makespan_first(times, ranks, setup):
    """The makespan with `setup` added to each rank's first task."""
    free = [(0.0, False)] * ranks
    heapq.heapify(free)
    for t in times:
        at, started = heapq.heappop(free)
        heapq.heappush(free, (at + t + (0.0 if started else setup), True))
    return max(at for at, _ in free)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("report", help="pipeline --report JSON of a one-thread run")
    ap.add_argument("--subjects", type=int, nargs="+", default=[200, 2000])
    ap.add_argument("--ranks", type=int, nargs="+", default=[1, 2, 8, 16, 32, 64])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--farm-only", action="store_true", help="leave rank 0's own part out (S = 0)")
    ap.add_argument("--dataset", action="store_true",
                    help="the report is of `pectus surrogate build` / `plan --dataset` (see above)")
    ap.add_argument("--serial-from", metavar="REPORT",
                    help="take S(N) from this run's report instead (a run of another size, e.g. 2000 subjects: "
                         "its rank-0 stages, scaled from its N as above)")
    ap.add_argument("--eig", metavar="N:SECONDS",
                    help="the eigen decomposition of an N x N Gram matrix took SECONDS on rank 0 (model_benchmark "
                         "model N); with a report of the model's steps, the part of the PCA rank 0 does alone")
    a = ap.parse_args()
    if a.dataset:
        dataset(a.report, a.ranks)
        return
    r = json.load(open(a.report))
    subjects = [s for s in r["subjects"]]
    phase_a = [sum(s["timings_s"].get(k, 0.0) for k in ("read", "merge", "reconstruct")) for s in subjects]
    phase_b = [sum(s["timings_s"].get(k, 0.0) for k in ("register", "resample", "measures")) for s in subjects]
    phase_c = [sum(s["timings_s"].get(k, 0.0) for k in ("distance", "files")) for s in subjects]
    n0 = len(subjects)
    total = r["timings_s"]
    phase_d = [total.get("pictures", 0.0) / n0] * n0
    eig_n, eig_s = (int(a.eig.split(":")[0]), float(a.eig.split(":")[1])) if a.eig else (1, 0.0)
    source, n_src = total, n0
    if a.serial_from:
        other = json.load(open(a.serial_from))
        source, n_src = other["timings_s"], len(other["subjects"])
    rank0 = rank0_model(source, n_src, eig_n, eig_s if a.eig else None, farmed_outputs=any(phase_c))
    print(f"measured: {n0} subjects; per subject surface {sum(phase_a)/n0:.3f} s, registration and grid "
          f"{sum(phase_b)/n0:.3f} s, distance and files {sum(phase_c)/n0:.3f} s, picture {phase_d[0]:.3f} s "
          f"(mean)")
    serial_src, shared_src, eig_src, inside_src = rank0(n_src)
    print(f"rank 0 and shared parts from {a.serial_from or a.report} ({n_src} subjects): rank 0 alone "
          f"{serial_src:.2f} s, shared among the ranks {shared_src:.2f} s"
          + (f", beside the third and fourth tasks: the eigen decomposition {eig_src:.2f} s on rank 0, "
             f"its reading the summaries back {inside_src:.2f} s" if eig_src else ""))
    rng = random.Random(a.seed)
    for n in a.subjects:
        if n == n0:
            ta, tb, tc, td = phase_a, phase_b, phase_c, phase_d
        else:
            draw = [rng.randrange(n0) for _ in range(n)]
            ta, tb, tc, td = ([t[i] for i in draw] for t in (phase_a, phase_b, phase_c, phase_d))
        serial, shared, eig, inside = (0.0, 0.0, 0.0, 0.0) if a.farm_only else rank0(n)
        if not a.farm_only and source.get("model files"):  # written on rank 0 beside its third tasks
            tc = list(tc) + [source["model files"] * n / n_src]
        outputs = 0.0 if a.farm_only else source.get("model outputs", 0.0) * n / n_src
        outputs_largest = source.get("model outputs largest", 0.0) * n / n_src
        t1 = sum(ta) + sum(tb) + sum(tc) + sum(td) + serial + shared + eig + inside + outputs
        for p in a.ranks:
            for largest, name in ((True, "largest first"), (False, "subject order")):
                order = (lambda t: sorted(t, reverse=True)) if largest else (lambda t: t)
                a_p, b_p, c_p, d_p = (makespan(order(t), p) for t in (ta, tb, tc, td))
                if eig and p > 1:
                    # rank 0's core decomposes and reads the summaries back while the other ranks run the
                    # third tasks, then (the colour scale read in shared blocks) the fourth
                    window = max(eig + inside, makespan(order(tc), p - 1) + makespan(order(td), p - 1))
                else:
                    window = eig + c_p + inside + d_p
                e_p = min(outputs, outputs / p + (1.0 - 1.0 / p) * outputs_largest)
                tp = serial + shared / p + a_p + b_p + window + e_p
                print(f"N={n:5d} P={p:3d} {name:14s} T={tp:9.1f} s  speed-up {t1/tp:6.2f}  "
                      f"efficiency {100*t1/(p*tp):5.1f} %  (rank 0 alone {serial:.1f} s, shared {shared/p:.1f} s)")


if __name__ == "__main__":
    main()
