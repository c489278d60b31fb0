#include "planner_plugin/host/plan_scoring.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "planner_plugin/host/depth_difference.h"
#include "shape/core/error.h"

namespace pectus::planner {
namespace {

DistanceStats StatsOf(const Eigen::VectorXd& values, const Eigen::Matrix<bool, Eigen::Dynamic, 1>* mask) {
  std::vector<double> kept;
  for (Eigen::Index i = 0; i < values.size(); ++i) {
    if (std::isfinite(values(i)) && (mask == nullptr || (*mask)(i))) kept.push_back(values(i));
  }
  return SummarizeDistances(
      Eigen::Map<const Eigen::VectorXd>(kept.data(), static_cast<Eigen::Index>(kept.size())));
}

// Points (#points by 3) moved by T.
Points3 ToAverage(const Similarity3& T, const Points3& x) {
  Points3 y(x.rows(), 3);
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    y.row(i) = (T * Eigen::Vector3d(x.row(i).transpose())).transpose();
  return y;
}

}  // namespace

bool PlanScoreOptions::IsValid(std::string* why) const {
  if (!(central_fraction > 0 && central_fraction <= 1)) {
    if (why) *why = "central_fraction must be in (0, 1]";
    return false;
  }
  return registration.IsValid(why);
}

nlohmann::json PlanScore::ToJson() const {
  nlohmann::json j = roi.ToJson();
  j["central"] = central_roi.ToJson();
  j["landmark_rms_mm"] = registration.landmark_rms_mm;
  j["scale"] = registration.T_target_source.scale;
  j["landmarks_used"] = registration.used;
  j["uncovered_vertices"] = uncovered;
  return j;
}

TriangleMesh PredictedChest(const PlanScore& score, const AverageChest& average, const TriangleMesh& skin,
                            bool relative, Eigen::VectorXd* difference_mm) {
  TriangleMesh chest;
  if (relative) {
    chest = average.mesh;
    const Eigen::Vector3d anterior = AnteriorDirection(average.mesh, "average chest");
    for (Eigen::Index i = 0; i < chest.num_vertices(); ++i) {
      const double d = score.difference_mm(i);
      if (std::isfinite(d)) chest.vertices.positions.row(i) += d * anterior.transpose();
    }
    *difference_mm = score.difference_mm;
  } else {
    chest.vertices.positions = score.predicted_in_average;
    chest.faces = skin.faces;
    *difference_mm = score.predicted_distance_mm;
  }
  return chest;
}

Eigen::Matrix<bool, Eigen::Dynamic, 1> CentralRegion(const AverageChest& average, double fraction) {
  const Eigen::Vector3d notch = average.landmarks.Position("sternal_notch", average.landmark_source);
  const Eigen::Vector3d axis = average.landmarks.Position("xiphoid", average.landmark_source) - notch;
  const Eigen::Vector3d e1 = axis.normalized();
  const Eigen::Vector3d anterior = AnteriorDirection(average.mesh, "average chest");
  const Eigen::Vector3d lateral = anterior.cross(e1).normalized();
  const Points3& x = average.mesh.vertices.positions;
  double u_max = 0;
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    u_max = std::max(u_max, std::abs((x.row(i).transpose() - notch).dot(lateral)));
  const double length = axis.norm();
  Eigen::Matrix<bool, Eigen::Dynamic, 1> central(x.rows());
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    const Eigen::Vector3d d = x.row(i).transpose() - notch;
    const double v = d.dot(e1) / length;
    central(i) = std::abs(v - 0.5) <= 0.5 * fraction && std::abs(d.dot(lateral)) <= fraction * u_max;
  }
  return central;
}

PlanScore ScorePlan(const TriangleMesh& skin, const LandmarkSet& landmarks, const AverageChest& average,
                    const PlanScoreOptions& options) {
  PlanScoreOptions modelled = options;
  modelled.relative = false;
  return ScorePlan(
      skin, Points3(),
      RegisterChestByLandmarks(landmarks, AnteriorDirection(skin, "predicted skin"), average.landmarks,
                               AnteriorDirection(average.mesh, "average chest"), options.registration),
      average, modelled);
}

PlanScorer::PlanScorer(const TriangleMesh& skin, const Points3& without_deformity,
                       const ChestRegistrationResult& registration, const AverageChest& average,
                       const PlanScoreOptions& options)
    : average_(&average),
      options_(options),
      registration_(registration),
      moved_(skin),
      anterior_(AnteriorDirection(average.mesh, "average chest")),
      probe_(average.mesh.vertices.positions, anterior_) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("plan scoring: " + why);
  if (options.relative && without_deformity.rows() != skin.num_vertices()) {
    ThrowUsage(
        "plan scoring: the relative skin model needs the skin without the deformity, vertex by vertex");
  }
  central_ = CentralRegion(average, options.central_fraction);
  if (options.relative) {
    TriangleMesh reference = skin;
    reference.vertices.positions = ToAverage(registration.T_target_source, without_deformity);
    reference_depth_ = probe_.Depth(reference);
  }
}

PlanScore PlanScorer::Score(const Points3& positions) const {
  if (positions.rows() != moved_.num_vertices()) {
    ThrowUsage("plan scoring: " + std::to_string(positions.rows()) + " skin vertices, the skin has " +
               std::to_string(moved_.num_vertices()));
  }
  PlanScore score;
  // Step 1: the predicted chest in the average chest's frame.
  score.registration = registration_;
  TriangleMesh moved = moved_;
  moved.vertices.positions = ToAverage(registration_.T_target_source, positions);
  const Points3& p = moved.vertices.positions;
  score.predicted_in_average = p;
  // Step 2: at every average-chest vertex, how far in front of it the predicted chest lies: directly
  // (modelled skin), or as the average chest carrying the deformity and correction (relative).
  score.difference_mm = probe_.Depth(moved);
  if (options_.relative) score.difference_mm -= reference_depth_;
  score.uncovered = score.difference_mm.array().isNaN().count();
  // Step 3: statistics over the region of interest and its central part.
  score.central = central_;
  score.roi = StatsOf(score.difference_mm, nullptr);
  score.central_roi = StatsOf(score.difference_mm, &score.central);
  // Step 4 (pictures): the same difference on the predicted skin, inside the average chest's extent.
  if (options_.map_predicted_skin && !options_.relative) {
    score.predicted_distance_mm = -DepthDifference(p, anterior_, average_->mesh);
  }
  return score;
}

double PlanScorer::Rms(const Points3& positions, bool central) const {
  if (positions.rows() != moved_.num_vertices()) {
    ThrowUsage("plan scoring: " + std::to_string(positions.rows()) + " skin vertices, the skin has " +
               std::to_string(moved_.num_vertices()));
  }
  return RmsOf(probe_.Depth(ToAverage(registration_.T_target_source, positions), moved_.faces), central);
}

PlanScorer::LinearSkin PlanScorer::Linearise(const Points3& skin0, const Points3& skin_per_n) const {
  if (skin0.rows() != moved_.num_vertices() || skin_per_n.rows() != moved_.num_vertices()) {
    ThrowUsage("plan scoring: a linear skin needs " + std::to_string(moved_.num_vertices()) + " vertices");
  }
  // T (s0 + F g) = T s0 + F s R g: the response turns and scales, it does not translate.
  const Similarity3& T = registration_.T_target_source;
  const Eigen::Matrix3d sR = T.scale * T.rotation;
  const Points3 turned = skin_per_n * sR.transpose();
  return {probe_.Project(ToAverage(T, skin0)), probe_.Project(turned)};
}

double PlanScorer::Rms(const LinearSkin& skin, double force_n, bool central) const {
  DepthProbe::Projected at;
  at.uv = skin.base.uv + force_n * skin.per_newton.uv;
  at.h = skin.base.h + force_n * skin.per_newton.h;
  return RmsOf(probe_.Depth(at, moved_.faces), central);
}

double PlanScorer::RmsOf(Eigen::VectorXd difference, bool central) const {
  if (options_.relative) difference -= reference_depth_;
  // As StatsOf then SummarizeDistances: the finite values in the region, in order.
  Eigen::Index kept = 0;
  for (Eigen::Index i = 0; i < difference.size(); ++i) {
    if (std::isfinite(difference(i)) && (!central || central_(i))) difference(kept++) = difference(i);
  }
  if (kept == 0) return 0.0;
  return std::sqrt(difference.head(kept).squaredNorm() / static_cast<double>(kept));
}

PlanScore ScorePlan(const TriangleMesh& skin, const Points3& without_deformity,
                    const ChestRegistrationResult& registration, const AverageChest& average,
                    const PlanScoreOptions& options) {
  return PlanScorer(skin, without_deformity, registration, average, options).Score(skin.vertices.positions);
}

}  // namespace pectus::planner
