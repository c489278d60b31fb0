// pectus register: the command's reports and cohort input (JSON of a pair's and a cohort's results; the
// scans of a cohort folder, read with the landmarks beside each), apart from its options and run steps.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "registration/align_cohort.h"
#include "registration/register_pair.h"
#include "shape/io/landmark_io.h"
#include "shape/io/mesh_io.h"

namespace pectus::cli {

/// The ICP result of a pair as report JSON: figures of the whole fit and of each level.
nlohmann::json IcpJson(const IcpResult& r);

/// The landmark alignment of a pair as report JSON: labels, RMS and residuals (mm), the transform.
nlohmann::json LandmarkJson(const LandmarkAlignmentResult& r);

/// What a pair's transform file holds beside T_target_source: the two scans and the fit's figures.
nlohmann::json PairTransformExtra(const std::string& moving, const std::string& fixed,
                                  const PairRegistrationResult& r);

/// The scans of a cohort folder (.ply, .obj, .stl, .pcd, .xyz in any case), sorted by name.
std::vector<std::filesystem::path> CohortScanFiles(const std::filesystem::path& folder);

/// Reads the scans `files` of a cohort in parallel, each named by its stem and with the landmarks beside
/// it (STEM.mrk.json, STEM.fcsv, STEM.csv or STEM.json) when there are any. Throws the first read error.
std::vector<CohortScan> ReadCohortScans(const std::vector<std::filesystem::path>& files,
                                        const ReadOptions& read_options,
                                        const LandmarkReadOptions& landmark_options);

/// A cohort's summary.json: the mode, the reference, one entry per scan (`files[i]` read into
/// `scans[i]`), and for the groupwise mode its iterations. The names of the failed scans, each with its
/// reason, go to `failed`.
nlohmann::json CohortSummary(const std::vector<std::filesystem::path>& files,
                             const std::vector<CohortScan>& scans, const CohortResult& r,
                             const CohortOptions& options, std::vector<std::string>* failed);

}  // namespace pectus::cli
