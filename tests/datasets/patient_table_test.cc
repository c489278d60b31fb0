// Tests of datasets/patient_table: a chest made from a row of the real CT table (read by shape/io's
// ReadPatientTable, tested in tests/shape/io/patient_table_io_test.cc) gives back that row's width, depth and
// depression (within 2 mm, the acceptance tolerance), measured independently on its surface.
#include "datasets/patient_table.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "datasets/synth.h"
#include "tests/support/require_shared_data.h"

namespace pectus::datasets {
namespace {

struct SliceMeasure {
  double width = 0, depth = 0, depression = 0;
};

// An independent measurement of one axial slice of the chest wall (the wall is a v-line: y depends on v
// only): 2001 points across; width = x extent; depth = front z to the back plane; depression = largest gap
// below the anterior (upper) convex hull in (x, z).
SliceMeasure MeasureSlice(const ChestSurface& wall, double v) {
  const int n = 2001;
  std::vector<Eigen::Vector2d> pts(n);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p = wall.Position(-1.0 + 2.0 * i / (n - 1), v);
    pts[i] = {p.x(), p.z()};
  }
  std::sort(pts.begin(), pts.end(), [](const auto& a, const auto& b) { return a.x() < b.x(); });
  std::vector<Eigen::Vector2d> hull;
  for (const Eigen::Vector2d& q : pts) {
    while (hull.size() >= 2) {
      const Eigen::Vector2d a = hull[hull.size() - 2], b = hull.back();
      if ((b.x() - a.x()) * (q.y() - a.y()) - (b.y() - a.y()) * (q.x() - a.x()) >= 0.0) {
        hull.pop_back();  // b lies on or below the chord a-q: not on the upper hull
      } else {
        break;
      }
    }
    hull.push_back(q);
  }
  SliceMeasure m;
  m.width = pts.back().x() - pts.front().x();
  double front = -1e9;
  std::size_t h = 0;
  for (const Eigen::Vector2d& q : pts) {
    front = std::max(front, q.y());
    while (h + 2 < hull.size() && hull[h + 1].x() <= q.x()) ++h;
    const Eigen::Vector2d a = hull[h], b = hull[std::min(h + 1, hull.size() - 1)];
    const double t = b.x() > a.x() ? (q.x() - a.x()) / (b.x() - a.x()) : 0.0;
    m.depression = std::max(m.depression, a.y() + t * (b.y() - a.y()) - q.y());
  }
  const ChestParameters& p = wall.parameters();
  m.depth = front + 0.5 * p.depth_mm * p.growth.z();
  return m;
}

// Acceptance: rows spanning the table (deepest depression 40 mm, flattest, narrowest, the validation patient
// 57).
TEST(PatientTable, SubjectFromARowGivesBackWidthDepthAndDepressionWithin2mm) {
  PECTUS_REQUIRE_SHARED_FILE(testing_support::kPatientTable);
  const std::vector<PatientTableRow> rows = ReadPatientTable(testing_support::PatientTablePath());
  std::vector<int> chosen = {57, 3};
  auto extreme = [&](auto key) {
    return std::min_element(rows.begin(), rows.end(),
                            [&](const auto& a, const auto& b) { return key(a) < key(b); })
        ->patient;
  };
  chosen.push_back(extreme([](const PatientTableRow& r) { return r.depression_mm; }));
  chosen.push_back(extreme([](const PatientTableRow& r) { return r.width_mm; }));
  chosen.push_back(extreme([](const PatientTableRow& r) { return -r.depth_mm; }));
  for (int number : chosen) {
    const PatientTableRow& row = FindPatient(rows, number, testing_support::PatientTablePath());
    const SyntheticSubject s = MakePatientSubject(row, 7, SubjectOptions{});
    const ChestSurface wall = s.ChestWall();
    // The slice of deepest depression over the sternal body (notch to xiphoid), every 0.5 % of the sternum.
    SliceMeasure best;
    for (int k = 0; k <= 200; ++k) {
      const SliceMeasure m = MeasureSlice(wall, kVXiphoid + (kVNotch - kVXiphoid) * (0.1 + 0.8 * k / 200.0));
      if (k == 0 || m.depression > best.depression) best = m;
    }
    // As MeasureChest documents: a concavity under 0.5 mm is none, and the slice is then the reference level.
    if (best.depression < 0.5) best = MeasureSlice(wall, kVReference);
    EXPECT_NEAR(best.width, row.width_mm, 2.0) << "patient " << number;
    EXPECT_NEAR(best.depth, row.depth_mm, 2.0) << "patient " << number;
    EXPECT_NEAR(best.depression, row.depression_mm, 2.0) << "patient " << number;
    EXPECT_NEAR(s.parameters.sternal_length_mm, row.sternal_length_mm, 1e-9);
  }
}

}  // namespace
}  // namespace pectus::datasets
