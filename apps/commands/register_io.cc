#include "apps/commands/register_io.h"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <exception>
#include <optional>

#include "shape/core/log.h"
#include "shape/io/transform_io.h"

namespace pectus::cli {
namespace fs = std::filesystem;
namespace {

// The landmark file beside a scan in a cohort folder: STEM.mrk.json, STEM.fcsv, STEM.csv or STEM.json.
std::optional<fs::path> LandmarksBeside(const fs::path& scan) {
  const fs::path dir = scan.parent_path();
  const std::string stem = scan.stem().string();
  for (const char* ext : {".mrk.json", ".fcsv", ".csv", ".json"}) {
    const fs::path p = dir / (stem + ext);
    if (fs::is_regular_file(p)) return p;
  }
  return std::nullopt;
}

}  // namespace

nlohmann::json IcpJson(const IcpResult& r) {
  nlohmann::json levels = nlohmann::json::array();
  for (const IcpLevelReport& l : r.levels) {
    levels.push_back({{"voxel_size_mm", l.voxel_size_mm},
                      {"max_distance_mm", l.max_distance_mm},
                      {"source_points", l.source_points},
                      {"target_points", l.target_points},
                      {"iterations", l.iterations},
                      {"converged", l.converged},
                      {"rms_mm", l.rms_mm},
                      {"searches", l.searches},
                      {"seconds", l.seconds}});
  }
  return {{"rms_mm", r.rms_mm},
          {"inlier_fraction", r.inlier_fraction},
          {"inliers", r.inliers},
          {"iterations", r.iterations},
          {"converged", r.converged},
          {"success", r.success},
          {"conditioning", r.conditioning},
          {"rotation_sd_deg", r.rotation_sd_deg},
          {"translation_sd_mm", r.translation_sd_mm},
          {"residual_scale_mm", r.residual_scale_mm},
          {"sampling_sd_mm", r.sampling_sd_mm},
          {"timings_s", r.timings_s.ToJson()},
          {"levels", levels},
          {"message", r.message}};
}

nlohmann::json LandmarkJson(const LandmarkAlignmentResult& r) {
  nlohmann::json residuals = nlohmann::json::object();
  for (std::size_t i = 0; i < r.labels.size(); ++i)
    residuals[r.labels[i]] = r.residuals_mm(static_cast<Eigen::Index>(i));
  return {{"labels", r.labels},
          {"rms_mm", r.rms_mm},
          {"residuals_mm", residuals},
          {"unmatched", r.unmatched},
          {"transform", TransformToJson(r.T_target_source)}};
}

nlohmann::json PairTransformExtra(const std::string& moving, const std::string& fixed,
                                  const PairRegistrationResult& r) {
  nlohmann::json extra = {{"source", moving}, {"target", fixed}, {"success", true}, {"message", r.message}};
  if (r.icp) {
    extra["rms_mm"] = r.icp->rms_mm;
    extra["inlier_fraction"] = r.icp->inlier_fraction;
    extra["iterations"] = r.icp->iterations;
    extra["converged"] = r.icp->converged;
  }
  if (r.landmarks) extra["landmark_rms_mm"] = r.landmarks->rms_mm;
  return extra;
}

std::vector<fs::path> CohortScanFiles(const fs::path& folder) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (!entry.is_regular_file()) continue;
    std::string ext = entry.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (ext == ".ply" || ext == ".obj" || ext == ".stl" || ext == ".pcd" || ext == ".xyz")
      files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::vector<CohortScan> ReadCohortScans(const std::vector<fs::path>& files, const ReadOptions& read_options,
                                        const LandmarkReadOptions& landmark_options) {
  std::vector<CohortScan> scans(files.size());
  Progress progress("reading scans", static_cast<std::int64_t>(files.size()));
  std::exception_ptr failure;
#pragma omp parallel for schedule(dynamic)
  for (std::size_t i = 0; i < files.size(); ++i) {
    try {
      scans[i].name = files[i].stem().string();
      scans[i].cloud = ReadPointCloud(files[i], read_options);
      if (const auto lm = LandmarksBeside(files[i]))
        scans[i].landmarks = ReadLandmarks(*lm, landmark_options);
    } catch (...) {
#pragma omp critical
      failure = std::current_exception();
    }
    progress.Advance();
  }
  if (failure) std::rethrow_exception(failure);
  return scans;
}

nlohmann::json CohortSummary(const std::vector<fs::path>& files, const std::vector<CohortScan>& scans,
                             const CohortResult& r, const CohortOptions& options,
                             std::vector<std::string>* failed) {
  const bool groupwise = options.mode == CohortMode::kGroupwise;
  nlohmann::json list = nlohmann::json::array();
  for (std::size_t i = 0; i < files.size(); ++i) {
    list.push_back({{"name", scans[i].name},
                    {"file", files[i].string()},
                    {"landmarks", scans[i].landmarks.has_value()},
                    {"success", static_cast<bool>(r.success[i])},
                    {"rms_mm", r.rms_mm[i]},
                    {"inlier_fraction", r.inlier_fraction[i]},
                    {"message", r.messages[i]},
                    {"transform", TransformToJson(r.T_frame_scan[i])}});
    if (!r.success[i]) failed->push_back(scans[i].name + " (" + r.messages[i] + ")");
  }
  nlohmann::json summary = {{"mode", groupwise ? "groupwise" : "to-reference"},
                            {"reference", scans[static_cast<std::size_t>(options.reference)].name},
                            {"frame", "the reference scan's frame"},
                            {"scans", list},
                            {"all_succeeded", failed->empty()},
                            {"failed", *failed}};
  if (groupwise) {
    summary["iterations"] = r.iterations;
    summary["converged"] = r.converged;
    if (r.procrustes) {
      summary["landmark_procrustes"] = {{"iterations", r.procrustes->iterations},
                                        {"rms_mm", r.procrustes->rms_mm},
                                        {"skipped_labels", r.procrustes->skipped}};
    }
  }
  return summary;
}

}  // namespace pectus::cli
