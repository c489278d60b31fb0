// model_benchmark: small pieces shared by the truth and population parts: clocks, principal angles, rigid
// alignment of shape vectors, and a generator surface through the pipeline's chain.
#pragma once

#include <sys/resource.h>

#include <Eigen/SVD>
#include <chrono>
#include <cmath>

#include "datasets/chest_landmarks.h"
#include "datasets/chest_population.h"
#include "datasets/surface_query.h"
#include "registration/landmark_alignment.h"
#include "shape/model/shape_grid.h"
#include "shape/pipeline/cohort_pipeline.h"

namespace pectus::bench {

/// Wall clock, seconds.
inline double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// CPU time of this process (user + system, all threads), seconds.
inline double CpuSeconds() {
  rusage r{};
  getrusage(RUSAGE_SELF, &r);
  return double(r.ru_utime.tv_sec) + 1e-6 * double(r.ru_utime.tv_usec) + double(r.ru_stime.tv_sec) +
         1e-6 * double(r.ru_stime.tv_usec);
}

/// Principal angles (degrees) between the spans of the first k columns of A and B (orthonormal columns).
inline Eigen::VectorXd PrincipalAnglesDeg(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, int k) {
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(A.leftCols(k).transpose() * B.leftCols(k));
  return svd.singularValues().array().min(1.0).acos() * 180.0 / M_PI;
}

/// The rigid motion T_target_shape that moves `shape` onto `target` (shape vectors, least squares over
/// corresponding vertices).
inline Similarity3 AlignmentTo(const Eigen::VectorXd& target, const Eigen::VectorXd& shape) {
  return UmeyamaAlignment(FromShapeVector(shape), FromShapeVector(target), {}, false, 0.0, "shape");
}

/// `shape` moved by T (every vertex).
inline Eigen::VectorXd Moved(const Similarity3& T, const Eigen::VectorXd& shape) {
  Points3 x = FromShapeVector(shape);
  for (Eigen::Index k = 0; k < x.rows(); ++k)
    x.row(k) = (T * Eigen::Vector3d(x.row(k).transpose())).transpose();
  return ToShapeVector(x);
}

/// `shape` moved rigidly onto `target`.
inline Eigen::VectorXd AlignedTo(const Eigen::VectorXd& target, const Eigen::VectorXd& shape) {
  return Moved(AlignmentTo(target, shape), shape);
}

/// RMS over vertices of the distances between two shape vectors, mm.
inline double RmsMm(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  const Eigen::VectorXd d = VertexDistances(a, b);
  return std::sqrt(d.squaredNorm() / double(d.size()));
}

/// A surface of the generator through the pipeline's chain, by the library's own stages: tessellated, cut
/// to its ROI + margin (CropToRoi, as the sweeps are), registered to the reference (RegisterSubject),
/// resampled (ResampleSubject). Returns the grid's shape vector. Thread-safe (the
/// pipeline runs the same calls on its subjects in parallel).
inline Eigen::VectorXd ThroughChain(const datasets::ChestSurface& surface, const IcpTarget& reference,
                                    const LandmarkSet& reference_landmarks, const PipelineOptions& options) {
  SubjectOutcome s;
  const TriangleMesh mesh = datasets::Tessellate(surface, 2.0);
  s.landmarks = datasets::TrueLandmarks(surface);
  s.surface.vertices =
      CropToRoi(mesh.vertices, ComputeChestRoi(s.landmarks, options.roi), options.crop_margin_mm);
  s.name = "generator surface";
  RegisterSubject(reference, reference_landmarks, options, &s);
  ResampleSubject(options, &s);
  return s.grid.shape_vector;
}

}  // namespace pectus::bench
