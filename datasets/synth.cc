#include "datasets/synth.h"

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <random>

#include "datasets/chest_landmarks.h"
#include "datasets/internal/validation.h"
#include "datasets/seeding.h"
#include "shape/core/error.h"
#include "shape/core/geometry.h"

namespace pectus::datasets {
namespace {

using internal::Fail;
using internal::InRange;

// Streams of a subject's own draws beyond the population sample (kept apart so that turning pectus or pose
// on does not change the shape).
enum class SubjectDraw : std::uint64_t { kPectus = 11, kPose = 12 };

std::mt19937_64 SubjectRng(std::uint64_t subject_seed, SubjectDraw what) {
  return std::mt19937_64(Mix64(subject_seed ^ Mix64(static_cast<std::uint64_t>(what))));
}

PectusParameters DrawPectus(const PectusDrawOptions& o, std::mt19937_64* rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0), sym(-1.0, 1.0);
  PectusParameters p;
  p.depth_mm = o.depth_min_mm + (o.depth_max_mm - o.depth_min_mm) * unit(*rng);
  p.type = unit(*rng) < o.cup_fraction ? PectusType::kCup : PectusType::kSaucer;
  p.centre_x_mm = o.max_centre_x_mm * sym(*rng);
  p.centre_y_mm = o.max_centre_y_mm * sym(*rng);
  p.asymmetry = o.max_asymmetry * sym(*rng);
  p.torsion_deg = o.max_torsion_deg * sym(*rng);
  return p;
}

Rigid3 DrawPose(double angle_deg, double shift_mm, std::mt19937_64* rng) {
  Rigid3 T = Rigid3::Identity();
  if (angle_deg > 0.0)
    T.linear() = Eigen::AngleAxisd(angle_deg * kDegree, RandomUnit(rng)).toRotationMatrix();
  if (shift_mm > 0.0) T.translation() = shift_mm * RandomUnit(rng);
  return T;
}

std::string SubjectName(int index) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "subject_%03d", index);
  return buffer;
}

void CheckOptions(const SubjectOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("subject options: " + why);
}

}  // namespace

bool PectusDrawOptions::IsValid(std::string* why) const {
  if (!InRange(fraction, 0.0, 1.0)) return Fail(why, "pectus fraction must be within [0, 1]");
  if (!InRange(depth_min_mm, 0.0, 60.0) || !InRange(depth_max_mm, depth_min_mm, 60.0)) {
    return Fail(why, "pectus depths must satisfy 0 <= min <= max <= 60 mm");
  }
  if (!InRange(cup_fraction, 0.0, 1.0)) return Fail(why, "cup fraction must be within [0, 1]");
  if (!InRange(max_centre_x_mm, 0.0, 80.0))
    return Fail(why, "pectus lateral offset must be within [0, 80] mm");
  if (!InRange(max_centre_y_mm, 0.0, 60.0))
    return Fail(why, "pectus vertical offset must be within [0, 60] mm");
  if (!InRange(max_asymmetry, 0.0, 0.6)) return Fail(why, "pectus asymmetry must be within [0, 0.6]");
  if (!InRange(max_torsion_deg, 0.0, 45.0))
    return Fail(why, "sternal torsion must be within [0, 45] degrees");
  return true;
}

bool SubjectOptions::IsValid(std::string* why) const {
  if (!population.IsValid(why)) return false;
  if (!pectus.IsValid(why)) return false;
  if (!InRange(pose_deg, 0.0, 90.0)) return Fail(why, "subject pose angle must be within [0, 90] degrees");
  if (!InRange(pose_mm, 0.0, 1000.0)) return Fail(why, "subject pose shift must be within [0, 1000] mm");
  if (!InRange(landmark_sd_mm, 0.0, 20.0))
    return Fail(why, "landmark placement error must be within [0, 20] mm");
  return true;
}

bool CohortOptions::IsValid(std::string* why) const {
  if (subjects < 1 || subjects > 10000) return Fail(why, "a cohort holds 1 to 10000 subjects");
  return subject.IsValid(why) && scan.IsValid(why);
}

SyntheticSubject MakeSubject(const SubjectOptions& options, std::uint64_t seed, int index) {
  CheckOptions(options);
  SyntheticSubject s;
  s.name = SubjectName(index);
  s.seed = DeriveSeed(seed, SeedStream::kSubject, static_cast<std::uint64_t>(index));
  const SubjectSample sample = SampleSubject(options.population, s.seed);
  s.parameters = sample.parameters;
  s.latent = sample.latent;
  s.origin = "population";
  std::mt19937_64 pectus_rng = SubjectRng(s.seed, SubjectDraw::kPectus);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  if (unit(pectus_rng) < options.pectus.fraction) {
    s.parameters.pectus = DrawPectus(options.pectus, &pectus_rng);
    s.origin = "population + pectus";
  }
  std::mt19937_64 pose_rng = SubjectRng(s.seed, SubjectDraw::kPose);
  s.parameters.T_scan_subject = DrawPose(options.pose_deg, options.pose_mm, &pose_rng);
  return s;
}

SyntheticSubject MakeSubjectWithPectus(const SubjectOptions& options, std::uint64_t seed, int index,
                                       const PectusParameters& pectus) {
  std::string why;
  if (!pectus.IsValid(&why)) ThrowUsage("pectus: " + why);
  SyntheticSubject s = MakeSubject(options, seed, index);
  s.parameters.pectus = pectus;
  s.origin = pectus.depth_mm > 0.0 ? "population + pectus" : "population";
  return s;
}

SyntheticSubject MakePatientSubject(const PatientTableRow& row, std::uint64_t seed,
                                    const SubjectOptions& options) {
  CheckOptions(options);
  SyntheticSubject s;
  s.name = "patient_" + std::to_string(row.patient);
  s.seed = DeriveSeed(seed, SeedStream::kSubject, static_cast<std::uint64_t>(row.patient));
  const PatientChest chest = MakePatientChest(row, s.seed, options.population);
  s.parameters = chest.parameters;
  s.origin = "patient " + std::to_string(row.patient);
  std::mt19937_64 pose_rng = SubjectRng(s.seed, SubjectDraw::kPose);
  s.parameters.T_scan_subject = DrawPose(options.pose_deg, options.pose_mm, &pose_rng);
  auto measured = [](const ChestMeasurement& m) {
    return nlohmann::json{{"width_mm", m.width_mm},
                          {"depth_mm", m.depth_mm},
                          {"depression_mm", m.depression_mm},
                          {"sternal_length_mm", m.sternal_length_mm},
                          {"slice_y_mm", m.slice_y_mm}};
  };
  s.extra["patient_row"] = {{"patient", row.patient},   {"haller_index", row.haller_index},
                            {"width_mm", row.width_mm}, {"sternal_length_mm", row.sternal_length_mm},
                            {"depth_mm", row.depth_mm}, {"depression_mm", row.depression_mm}};
  s.extra["measured_chest_wall"] = measured(chest.wall);
  s.extra["measured_skin"] = measured(chest.skin);
  s.extra["fit_iterations"] = chest.iterations;
  s.extra["fit_residual_mm"] = chest.residual_mm;
  return s;
}

SyntheticSubject GrowSubject(const SyntheticSubject& subject, const GrowthOptions& growth,
                             const std::string& name) {
  SyntheticSubject s = subject;
  s.name = name;
  s.parameters = Grow(subject.parameters, growth);
  s.origin = "growth of " + subject.name;
  s.extra["growth"] = {
      {"years", growth.years},
      {"width_per_year", growth.width_per_year},
      {"depth_per_year", growth.depth_per_year},
      {"height_per_year", growth.height_per_year},
      {"pectus_depth_factor", growth.pectus_depth_factor},
      {"scale_xyz", {s.parameters.growth.x(), s.parameters.growth.y(), s.parameters.growth.z()}}};
  return s;
}

LandmarkSet PlaceLandmarks(const ChestSurface& surface, double sd_mm, std::uint64_t seed) {
  if (!InRange(sd_mm, 0.0, 20.0)) ThrowUsage("landmark placement error must be within [0, 20] mm");
  LandmarkSet set = TrueLandmarks(surface);
  if (sd_mm == 0.0) return set;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, sd_mm);
  const std::vector<LandmarkDefinition>& definitions = ChestLandmarkDefinitions();
  for (std::size_t i = 0; i < definitions.size(); ++i) {
    // A tangential step d, turned into a parameter step by least squares on the tangent plane (J du = d).
    const SurfacePoint sp = surface.Evaluate(definitions[i].u, definitions[i].v);
    const Eigen::Vector3d t1 = sp.d_du.normalized(), t2 = sp.normal.cross(t1);
    const Eigen::Vector3d d = normal(rng) * t1 + normal(rng) * t2;
    Eigen::Matrix<double, 3, 2> J;
    J << sp.d_du, sp.d_dv;
    const Eigen::Vector2d step = (J.transpose() * J).ldlt().solve(J.transpose() * d);
    const double u = std::clamp(definitions[i].u + step.x(), kUMin, kUMax);
    const double v = std::clamp(definitions[i].v + step.y(), kVMin, kVMax);
    set.items[i].position = surface.Position(u, v);
  }
  return set;
}

ScannedSubject ScanSubject(const SyntheticSubject& subject, const ScanOptions& scan, double landmark_sd_mm,
                           std::uint64_t seed) {
  ScannedSubject out;
  out.subject = subject;
  out.scan_seed = seed;
  out.options = scan;
  const ChestSurface skin = subject.Skin();
  out.scan = SimulateScan(skin, scan, seed);
  out.true_landmarks = TrueLandmarks(skin);
  out.placed_landmarks = PlaceLandmarks(skin, landmark_sd_mm, Mix64(seed ^ 0x6c616e646d61726bull));
  return out;
}

std::uint64_t CohortScanSeed(std::uint64_t seed, int index) {
  return DeriveSeed(seed, SeedStream::kScan, static_cast<std::uint64_t>(index) + 1);
}

std::vector<SyntheticSubject> MakeCohortSubjects(const CohortOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("cohort options: " + why);
  std::vector<SyntheticSubject> subjects;
  subjects.reserve(static_cast<std::size_t>(options.subjects));
  for (int i = 0; i < options.subjects; ++i)
    subjects.push_back(MakeSubject(options.subject, options.seed, i));
  return subjects;
}

nlohmann::json SubjectJson(const SyntheticSubject& subject) {
  nlohmann::json j;
  j["name"] = subject.name;
  j["seed"] = subject.seed;
  j["origin"] = subject.origin;
  j["parameters"] = ToJson(subject.parameters);
  j["latent"] = std::vector<double>(subject.latent.data(), subject.latent.data() + subject.latent.size());
  j["extra"] = subject.extra;
  return j;
}

SyntheticSubject SubjectFromJson(const nlohmann::json& j, const std::string& what) {
  if (!j.is_object() || !j.contains("parameters"))
    ThrowBadInput(what, "not a subject description (no \"parameters\")");
  SyntheticSubject s;
  try {
    s.name = j.value("name", std::string());
    s.seed = j.value("seed", std::uint64_t{0});
    s.origin = j.value("origin", std::string());
    if (j.contains("latent")) {
      const auto latent = j["latent"].get<std::vector<double>>();
      s.latent = Eigen::Map<const Eigen::VectorXd>(latent.data(), static_cast<Eigen::Index>(latent.size()));
    }
    if (j.contains("extra")) s.extra = j["extra"];
  } catch (const nlohmann::json::exception& e) {
    ThrowBadInput(what, std::string("malformed subject description: ") + e.what());
  }
  s.parameters = ChestParametersFromJson(j["parameters"], what);
  return s;
}

}  // namespace pectus::datasets
