// pectus datasets: synthetic subjects (population, pectus, patient, growth) and their scans with every truth,
// the entry point other stages call to make data with a known answer (docs/datasets.md).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "datasets/chest_parameters.h"
#include "datasets/chest_population.h"
#include "datasets/chest_surface.h"
#include "datasets/patient_table.h"
#include "datasets/scan_simulator.h"
#include "shape/core/landmarks.h"

namespace pectus::datasets {

/// Ranges from which a cohort's pectus excavatum cases are drawn (uniformly).
struct PectusDrawOptions {
  double fraction = 0.0;          ///< share of subjects given a depression, [0, 1]
  double depth_min_mm = 10.0;     ///< shallowest drawn depression, mm
  double depth_max_mm = 50.0;     ///< deepest drawn depression, mm (at most 60)
  double cup_fraction = 0.3;      ///< share of the cases that are cup type (the rest saucer), [0, 1]
  double max_centre_x_mm = 15.0;  ///< |lateral offset of the centre| up to this, mm
  double max_centre_y_mm = 15.0;  ///< |vertical offset from the reference level| up to this, mm
  double max_asymmetry = 0.3;     ///< |asymmetry| up to this, [0, 0.6]
  double max_torsion_deg = 20.0;  ///< |sternal torsion| up to this, degrees, [0, 45]

  bool IsValid(std::string* why) const;
};

/// How subjects are made.
struct SubjectOptions {
  PopulationModel population = PopulationModel::Default();
  PectusDrawOptions pectus;  ///< none by default
  double pose_deg = 0.0;     ///< the subject lies in the scanner's frame turned by this angle about a random
                             ///< axis (0: the scan frame is the chest frame), [0, 90]
  double pose_mm = 0.0;      ///< ... and shifted by this length in a random direction, mm, [0, 1000]
  double landmark_sd_mm = 0.0;  ///< placement error of the landmarks written beside the scan (moved along the
                                ///< surface, so they stay on it), mm, [0, 20]; the truth keeps exact ones

  bool IsValid(std::string* why) const;
};

/// Everything true about one subject (its shape; a scan of it is ScannedSubject).
struct SyntheticSubject {
  std::string name;            ///< folder name, "subject_000", "patient_57", "post"
  std::uint64_t seed = 0;      ///< the seed its shape was drawn with
  std::string origin;          ///< "population", "population + pectus", "patient 57", "growth of pre"
  ChestParameters parameters;  ///< the exact shape (ChestSurface(parameters) is the skin in the scan frame)
  Eigen::VectorXd latent;      ///< the population factors b_k (standard normal); empty for a patient
  nlohmann::json extra = nlohmann::json::object();  ///< patient row and fit, growth, ...

  /// The skin (what the scanner sees), at breathing state `breathing_mm` (0: reference).
  ChestSurface Skin(double breathing_mm = 0.0) const {
    return ChestSurface(parameters, Layer::kSkin, breathing_mm);
  }
  /// The outer surface of the ribcage and sternum.
  ChestSurface ChestWall() const { return ChestSurface(parameters, Layer::kChestWall); }
};

/// Draws subject `index` of a cohort seeded `seed`: latent factors and detail from the population, a
/// depression with probability options.pectus.fraction, a pose in the scan frame. Same (seed, index): same
/// subject.
SyntheticSubject MakeSubject(const SubjectOptions& options, std::uint64_t seed, int index);

/// A subject with a given depression (e.g. `pectus synth subject --pectus-depth 30`): the population draw of
/// MakeSubject, with `pectus` in place of any drawn one.
SyntheticSubject MakeSubjectWithPectus(const SubjectOptions& options, std::uint64_t seed, int index,
                                       const PectusParameters& pectus);

/// A patient's chest from a row of the CT table (MakePatientChest), named "patient_<n>"; extra holds the row
/// and the measurement of the result's chest wall and skin.
SyntheticSubject MakePatientSubject(const PatientTableRow& row, std::uint64_t seed,
                                    const SubjectOptions& options);

/// The same subject after growth (Grow), named `name`; extra holds the growth.
SyntheticSubject GrowSubject(const SyntheticSubject& subject, const GrowthOptions& growth,
                             const std::string& name);

/// A subject with its scan and landmarks: what a subject folder holds.
struct ScannedSubject {
  SyntheticSubject subject;
  Scan scan;
  LandmarkSet true_landmarks;    ///< exactly on the skin, scan frame (TrueLandmarks)
  LandmarkSet placed_landmarks;  ///< as a clinician placed them: moved along the skin by landmark_sd_mm
  ScanOptions options;           ///< how it was scanned
  std::uint64_t scan_seed = 0;
};

/// Scans a subject (SimulateScan with a seed derived from `seed`) and places its landmarks.
ScannedSubject ScanSubject(const SyntheticSubject& subject, const ScanOptions& scan, double landmark_sd_mm,
                           std::uint64_t seed);

/// Landmarks moved from their true (u, v) by a tangential Gaussian step of `sd_mm` per axis, so that they
/// stay exactly on the surface. sd_mm = 0 gives TrueLandmarks.
LandmarkSet PlaceLandmarks(const ChestSurface& surface, double sd_mm, std::uint64_t seed);

/// A whole cohort: `subjects` subjects drawn with MakeSubject(options.subject, seed, i), each scanned.
struct CohortOptions {
  int subjects = 11;  ///< [1, 10000]
  std::uint64_t seed = 7;
  SubjectOptions subject;
  ScanOptions scan;

  bool IsValid(std::string* why) const;
};

/// The subjects of a cohort (shapes only; scanning them is ScanSubject, done by the writer one at a time so
/// that a large cohort never sits in memory).
std::vector<SyntheticSubject> MakeCohortSubjects(const CohortOptions& options);

/// The seed of subject i's scan in a cohort seeded `seed`.
std::uint64_t CohortScanSeed(std::uint64_t seed, int index);

/// A JSON description of a subject: name, seed, origin, parameters, latent, extra.
nlohmann::json SubjectJson(const SyntheticSubject& subject);
/// Reads what SubjectJson wrote; throws Error(kBadInput) naming `what`.
SyntheticSubject SubjectFromJson(const nlohmann::json& j, const std::string& what);

}  // namespace pectus::datasets
