#include "datasets/scan_writer.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "datasets/chest_landmarks.h"
#include "datasets/surface_query.h"
#include "shape/core/atomic_file.h"
#include "shape/core/error.h"
#include "shape/io/landmark_io.h"
#include "shape/io/mesh_io.h"
#include "shape/io/stanford_conf.h"
#include "shape/io/transform_io.h"

namespace pectus::datasets {
namespace fs = std::filesystem;
namespace {

// Writes through the stage function and adds the written size to `bytes`.
class Writer {
 public:
  Writer(fs::path folder, const StagePath& stage) : folder_(std::move(folder)), stage_(stage) {}
  template <typename WriteFn>
  void Write(const std::string& relative, WriteFn write) {
    const fs::path target = folder_ / relative;
    const fs::path path = stage_ ? stage_(target) : target;
    write(path);
    std::error_code ec;
    const std::uintmax_t size = fs::file_size(path, ec);
    if (!ec) bytes_ += size;
  }
  std::uintmax_t bytes() const { return bytes_; }

 private:
  fs::path folder_;
  const StagePath& stage_;
  std::uintmax_t bytes_ = 0;
};

nlohmann::json Vector(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

nlohmann::json ScanOptionsJson(const ScanOptions& o) {
  nlohmann::json j = {{"sweeps", o.sweeps},
                      {"overlap", o.overlap},
                      {"spacing_mm", o.spacing_mm},
                      {"standoff_mm", o.standoff_mm},
                      {"noise_mm", o.noise_mm},
                      {"tracker_deg", o.tracker_deg},
                      {"tracker_mm", o.tracker_mm},
                      {"breathing_mm", o.breathing_mm},
                      {"subject_holes", o.subject_holes},
                      {"sweep_holes", o.sweep_holes},
                      {"hole_min_mm", o.hole_min_mm},
                      {"hole_max_mm", o.hole_max_mm},
                      {"ragged_mm", o.ragged_mm},
                      {"outlier_fraction", o.outlier_fraction},
                      {"max_incidence_deg", o.max_incidence_deg},
                      {"incidence_falloff", o.incidence_falloff},
                      {"tremor_mm", o.tremor_mm},
                      {"tremor_deg", o.tremor_deg}};
  // The widened scanner's options only where one is used, so that the original's files stay as they were.
  if (!o.IsOriginalScanner()) {
    j["sampling"] = ToString(o.sampling);
    j["pattern"] = ToString(o.pattern);
    j["tracker_pivot"] = ToString(o.tracker_pivot);
    j["tracker_lever_mm"] = o.tracker_lever_mm;
    j["tracker_draw"] = ToString(o.tracker_draw);
    j["tracker_skin_mm"] = o.tracker_skin_mm;
  }
  return j;
}

void WriteJson(const fs::path& path, const nlohmann::json& j) { WriteFileAtomically(path, j.dump(2) + "\n"); }

nlohmann::json ReadJson(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) ThrowBadInput(path.string(), "cannot open");
  std::stringstream buffer;
  buffer << in.rdbuf();
  try {
    return nlohmann::json::parse(buffer.str());
  } catch (const nlohmann::json::exception& e) {
    ThrowBadInput(path.string(), std::string("malformed JSON: ") + e.what());
  }
}

}  // namespace

bool SubjectWriteOptions::IsValid(std::string* why) const {
  if (!(truth_spacing_mm >= 0.2 && truth_spacing_mm <= 50.0)) {
    if (why) *why = "truth mesh spacing must be within [0.2, 50] mm";
    return false;
  }
  return true;
}

std::string SweepFileName(int sweep) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "sweep_%02d.ply", sweep);
  return buffer;
}

std::string SweepTruthFileName(int sweep) { return "truth/" + SweepFileName(sweep); }

std::uintmax_t WriteSubjectFolder(const ScannedSubject& s, const fs::path& folder,
                                  const SubjectWriteOptions& options, const StagePath& stage) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("subject folder: " + why);
  Writer out(folder, stage);
  WriteOptions binary;
  binary.comment = "pectus synth: " + s.subject.name + " (" + s.subject.origin + "), chest frame mm";
  nlohmann::json sweeps = nlohmann::json::array();
  std::vector<ScanPose> conf;
  for (std::size_t k = 0; k < s.scan.sweeps.size(); ++k) {
    const Sweep& sweep = s.scan.sweeps[k];
    const SweepTruth& t = sweep.truth;
    const int index = static_cast<int>(k);
    out.Write(SweepFileName(index), [&](const fs::path& p) { WritePointCloud(p, sweep.cloud, binary); });
    if (options.sweep_truth) {
      PointCloud truth;
      truth.positions = t.true_points;
      truth.scalars["u"] = t.u;
      truth.scalars["v"] = t.v;
      Eigen::VectorXd outlier(static_cast<Eigen::Index>(t.outlier.size()));
      for (std::size_t i = 0; i < t.outlier.size(); ++i) outlier(static_cast<Eigen::Index>(i)) = t.outlier[i];
      truth.scalars["outlier"] = outlier;
      out.Write(SweepTruthFileName(index), [&](const fs::path& p) { WritePointCloud(p, truth, binary); });
    }
    std::size_t outliers = 0;
    for (std::uint8_t o : t.outlier) outliers += o;
    nlohmann::json j = TransformToJson(Similarity3::FromRigid(t.T_scan_sweep));
    j["file"] = SweepFileName(index);
    j["points"] = sweep.cloud.size();
    j["outliers"] = outliers;
    j["lines"] = t.lines;
    j["tracker_rotation_error_deg"] = t.rotation_error_deg;
    j["tracker_translation_error_mm"] = t.translation_error_mm;
    j["tracker_pivot_mm"] = Vector(t.pivot);
    j["breathing_mm"] = t.breathing_mm;
    j["strip_u"] = {t.strip_u0, t.strip_u1};
    if (!s.options.IsOriginalScanner()) {
      j["strip_v"] = {t.strip_v0, t.strip_v1};
      j["tracker_skin_rms_mm"] = t.skin_rms_mm;
    }
    sweeps.push_back(j);
    conf.push_back({"../" + SweepFileName(index), t.T_scan_sweep});
  }
  nlohmann::json holes = nlohmann::json::array();
  for (const ScanHole& h : s.scan.holes) {
    holes.push_back({{"centre_mm", Vector(h.centre)},
                     {"uv", {h.uv.x(), h.uv.y()}},
                     {"diameter_mm", h.diameter_mm},
                     {"sweep", h.sweep},
                     {"cause", h.cause}});
  }
  nlohmann::json poses = {{"convention",
                           "x_scan = T_scan_sweep * x_sweep: maps each sweep file's points onto the "
                           "true surface (the inverse of the tracker's error)"},
                          {"scan_seed", s.scan_seed},
                          {"scan_options", ScanOptionsJson(s.options)},
                          {"sweeps", sweeps},
                          {"holes", holes}};
  out.Write(kPosesFile, [&](const fs::path& p) { WriteJson(p, poses); });
  out.Write(kPosesConfFile, [&](const fs::path& p) { WriteStanfordConf(p, conf); });
  out.Write(kLandmarksFile, [&](const fs::path& p) { WriteLandmarks(p, s.placed_landmarks); });
  out.Write(kTrueLandmarksFile, [&](const fs::path& p) { WriteLandmarks(p, s.true_landmarks); });
  const ChestSurface skin = s.subject.Skin();
  out.Write(kSurfaceFile,
            [&](const fs::path& p) { WriteMesh(p, Tessellate(skin, options.truth_spacing_mm), binary); });
  if (options.chest_wall) {
    const ChestSurface wall = s.subject.ChestWall();
    out.Write(kChestWallFile,
              [&](const fs::path& p) { WriteMesh(p, Tessellate(wall, options.truth_spacing_mm), binary); });
  }
  nlohmann::json subject = SubjectJson(s.subject);
  subject["frame"] =
      "chest frame, mm: x to the subject's left, y up (superior), z anterior; T_scan_subject places it";
  subject["pectus_amplitude_mm"] = skin.pectus_amplitude_mm();
  out.Write(kSubjectFile, [&](const fs::path& p) { WriteJson(p, subject); });
  return out.bytes();
}

void WritePopulationFolder(const PopulationModel& population, const TrueShapeStatistics& statistics,
                           const fs::path& folder, const StagePath& stage) {
  Writer out(folder, stage);
  const ShapeGrid& g = statistics.grid;
  const ChestSurface mean(population.mean);
  const TriangleMesh grid = TessellateGrid(mean, g.nu, g.nv, g.u0, g.u1, g.v0, g.v1);
  WriteOptions binary;
  binary.comment = "pectus synth: the population's exact mean skin on the shape grid (k = j * nu + i)";
  out.Write("population.json",
            [&](const fs::path& p) { WriteJson(p, PopulationJson(population, statistics)); });
  out.Write("mean.ply", [&](const fs::path& p) { WriteMesh(p, grid, binary); });
  for (std::size_t j = 0; j < statistics.modes.size(); ++j) {
    TriangleMesh mode = grid;
    mode.vertices.normals.resize(0, 3);
    mode.vertices.scalars["dx"] = statistics.modes[j].col(0);
    mode.vertices.scalars["dy"] = statistics.modes[j].col(1);
    mode.vertices.scalars["dz"] = statistics.modes[j].col(2);
    char name[32], comment[160];
    std::snprintf(name, sizeof(name), "mode_%02d.ply", static_cast<int>(j + 1));
    std::snprintf(comment, sizeof(comment),
                  "pectus synth: true mode %d (unit vector dx dy dz), eigenvalue %.9g mm^2",
                  static_cast<int>(j + 1), statistics.eigenvalues(static_cast<Eigen::Index>(j)));
    WriteOptions w;
    w.comment = comment;
    out.Write(name, [&](const fs::path& p) { WriteMesh(p, mode, w); });
  }
  out.Write("mean_landmarks.mrk.json", [&](const fs::path& p) { WriteLandmarks(p, TrueLandmarks(mean)); });
}

SubjectFolder ReadSubjectFolder(const fs::path& folder) {
  SubjectFolder f;
  f.folder = folder;
  const fs::path subject_path = folder / kSubjectFile;
  f.subject = SubjectFromJson(ReadJson(subject_path), subject_path.string());
  const fs::path poses_path = folder / kPosesFile;
  const nlohmann::json poses = ReadJson(poses_path);
  if (!poses.contains("sweeps") || !poses["sweeps"].is_array())
    ThrowBadInput(poses_path.string(), "no \"sweeps\" list");
  for (std::size_t k = 0; k < poses["sweeps"].size(); ++k) {
    const nlohmann::json& j = poses["sweeps"][k];
    const Similarity3 T = ParseTransformJson(j.dump(), poses_path.string());
    f.T_scan_sweep.push_back(T.RigidPart());
    f.sweeps.push_back(ReadPointCloud(folder / SweepFileName(static_cast<int>(k))));
    const fs::path truth = folder / SweepTruthFileName(static_cast<int>(k));
    if (fs::exists(truth)) f.sweep_truth.push_back(ReadPointCloud(truth));
  }
  f.landmarks = ReadLandmarks(folder / kLandmarksFile);
  f.true_landmarks = ReadLandmarks(folder / kTrueLandmarksFile);
  return f;
}

}  // namespace pectus::datasets
