#include "datasets/patient_table.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace pectus::datasets {

PatientChest MakePatientChest(const PatientTableRow& row, std::uint64_t seed,
                              const PopulationModel& population, const PatientFitOptions& options) {
  PatientChest out;
  ChestParameters& p = out.parameters;
  p = population.mean;
  // Soft tissue: the adult mean scaled by the patient's size; detail drawn like a population subject's.
  const double ratio = row.width_mm / population.mean.width_mm;
  const double tissue = options.soft_tissue_scale * ratio;
  p.soft_tissue_mm *= tissue;
  p.pectoral_mm *= tissue;
  p.breast_mm *= tissue;
  p.sternal_groove_mm *= tissue;
  p.concavity_mm *= tissue;
  p.notch_mm *= ratio;
  p.clavicle_mm *= ratio;
  p.costal_recession_mm *= ratio;
  p.costal_ridge_mm *= ratio;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, population.detail_sd_mm * tissue);
  p.detail_mm.resize(kDetailCoefficients);
  for (int i = 0; i < kDetailCoefficients; ++i) p.detail_mm(i) = normal(rng);
  p.sternal_length_mm = row.sternal_length_mm;
  p.width_mm = row.width_mm;
  p.depth_mm = row.depth_mm;
  p.pectus.type = PectusType::kSaucer;
  p.pectus.depth_mm = row.depression_mm;
  // Each measured quantity depends mostly on its own parameter: secant steps per quantity, starting from
  // a unit slope (a depression's measured depth is less than its deformation depth, by the chest's
  // curvature).
  double* parameter[3] = {&p.width_mm, &p.depth_mm, &p.pectus.depth_mm};
  const double target[3] = {row.width_mm, row.depth_mm, row.depression_mm};
  double slope[3] = {1.0, 1.0, 1.0}, last_value[3] = {0, 0, 0}, last_measured[3] = {0, 0, 0};
  for (out.iterations = 1; out.iterations <= options.max_iterations; ++out.iterations) {
    out.wall = MeasureChest(ChestSurface(p, Layer::kChestWall));
    const double measured[3] = {out.wall.width_mm, out.wall.depth_mm, out.wall.depression_mm};
    out.residual_mm = 0.0;
    for (int k = 0; k < 3; ++k)
      out.residual_mm = std::max(out.residual_mm, std::abs(target[k] - measured[k]));
    if (out.residual_mm < options.tolerance_mm) break;
    bool moved = false;
    for (int k = 0; k < 3; ++k) {
      if (out.iterations > 1 && std::abs(*parameter[k] - last_value[k]) > 1e-9) {
        slope[k] = std::clamp((measured[k] - last_measured[k]) / (*parameter[k] - last_value[k]), 0.2, 3.0);
      }
      last_value[k] = *parameter[k];
      last_measured[k] = measured[k];
      double next = *parameter[k] + (target[k] - measured[k]) / slope[k];
      if (k == 2) next = std::clamp(next, 0.0, 60.0);  // the depression's deformation depth
      moved |= std::abs(next - *parameter[k]) > 1e-9;
      *parameter[k] = next;
    }
    if (!moved) break;  // at a bound (a row asking for less than nothing, or more than 60 mm)
  }
  out.iterations = std::min(out.iterations, options.max_iterations);
  out.skin = MeasureChest(ChestSurface(p, Layer::kSkin));
  return out;
}

}  // namespace pectus::datasets
