#include "datasets/patient_table.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <random>
#include <sstream>

#include "shape/core/error.h"

namespace pectus::datasets {
namespace {

std::vector<std::string> SplitCsv(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  std::stringstream in(line);
  while (std::getline(in, cell, ',')) {
    const auto first = cell.find_first_not_of(" \t\r");
    const auto last = cell.find_last_not_of(" \t\r");
    cells.push_back(first == std::string::npos ? std::string() : cell.substr(first, last - first + 1));
  }
  return cells;
}

double ParseNumber(const std::string& text, const std::string& file, int line, const std::string& column) {
  double value = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size() || !std::isfinite(value)) {
    ThrowBadInput(file, "column " + column + ": '" + text + "' is not a number", line);
  }
  return value;
}

}  // namespace

std::vector<PatientRow> ReadPatientTable(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::ifstream in(path);
  if (!in) ThrowBadInput(file, "cannot open the patient table");
  std::string line;
  int number = 0;
  std::map<std::string, std::size_t> column;
  const char* needed[] = {"patient",           "haller_index", "width_mm",
                          "sternal_length_mm", "depth_mm",     "depression_mm"};
  std::vector<PatientRow> rows;
  while (std::getline(in, line)) {
    ++number;
    if (line.find_first_not_of(" \t\r") == std::string::npos || line[0] == '#') continue;
    const std::vector<std::string> cells = SplitCsv(line);
    if (column.empty()) {
      for (std::size_t c = 0; c < cells.size(); ++c) column[cells[c]] = c;
      for (const char* name : needed) {
        if (!column.count(name))
          ThrowBadInput(file, std::string("the header has no column '") + name + "'", number);
      }
      continue;
    }
    auto cell = [&](const char* name) {
      const std::size_t c = column[name];
      if (c >= cells.size()) ThrowBadInput(file, std::string("missing value of column ") + name, number);
      return ParseNumber(cells[c], file, number, name);
    };
    PatientRow row;
    row.line = number;
    const double patient = cell("patient");
    if (patient != std::floor(patient) || patient < 1 || patient > 1e6) {
      ThrowBadInput(file, "patient number must be a positive whole number", number);
    }
    row.patient = static_cast<int>(patient);
    row.haller_index = cell("haller_index");
    row.width_mm = cell("width_mm");
    row.sternal_length_mm = cell("sternal_length_mm");
    row.depth_mm = cell("depth_mm");
    row.depression_mm = cell("depression_mm");
    if (row.width_mm < 120 || row.width_mm > 500 || row.depth_mm < 60 || row.depth_mm > 400 ||
        row.sternal_length_mm < 60 || row.sternal_length_mm > 300 || row.depression_mm < 0 ||
        row.depression_mm > 60) {
      ThrowBadInput(
          file, "measurements out of range (width 120-500, depth 60-400, length 60-300, depression 0-60 mm)",
          number);
    }
    for (const PatientRow& r : rows) {
      if (r.patient == row.patient) {
        ThrowBadInput(file,
                      "patient " + std::to_string(row.patient) + " already on line " + std::to_string(r.line),
                      number);
      }
    }
    rows.push_back(row);
  }
  if (column.empty()) ThrowBadInput(file, "empty patient table");
  return rows;
}

const PatientRow& FindPatient(const std::vector<PatientRow>& rows, int number, const std::string& table) {
  for (const PatientRow& r : rows) {
    if (r.patient == number) return r;
  }
  ThrowBadInput(table, "has no patient " + std::to_string(number));
}

PatientChest MakePatientChest(const PatientRow& row, std::uint64_t seed, const PopulationModel& population,
                              const PatientFitOptions& options) {
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
