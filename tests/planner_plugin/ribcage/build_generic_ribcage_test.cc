#include "planner_plugin/ribcage/build_generic_ribcage.h"

#include <gtest/gtest.h>

#include <map>
#include <numeric>

#include "planner_plugin/fem/tet_mesh.h"
#include "planner_plugin/ribcage/ribcage_measurements.h"
#include "shape/core/error.h"

namespace pectus::planner {
namespace {

// Number of connected components of the tetrahedra (sharing a node).
int Components(const Tet4Connectivity& tets, Eigen::Index num_nodes) {
  std::vector<int> parent(static_cast<std::size_t>(num_nodes));
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (Eigen::Index t = 0; t < tets.rows(); ++t) {
    for (int k = 1; k < 4; ++k) parent[find(tets(t, k))] = find(tets(t, 0));
  }
  std::vector<char> used(static_cast<std::size_t>(num_nodes), 0);
  for (Eigen::Index t = 0; t < tets.rows(); ++t) {
    for (int k = 0; k < 4; ++k) used[tets(t, k)] = 1;
  }
  int count = 0;
  for (Eigen::Index i = 0; i < num_nodes; ++i) count += used[i] && find(static_cast<int>(i)) == i;
  return count;
}

TEST(GenericRibcage, IsOneConformingSolidWithThreeMaterials) {
  const GenericRibcage g = BuildGenericRibcage();
  const TetMesh mesh = MakeQuadratic(g.nodes, g.tets, g.regions);
  mesh.Validate("generic ribcage");  // every tetrahedron positive
  EXPECT_EQ(Components(g.tets, g.nodes.rows()), 1) << "sternum, ribs and cartilages must form one structure";
  // Conforming and closed: every directed boundary edge appears once, and its reverse once.
  Eigen::VectorXi face_tet;
  const Faces3 faces = ExtractLinearBoundary(g.tets, &face_tet);
  std::map<std::pair<int, int>, int> directed;
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    for (int i = 0; i < 3; ++i) ++directed[{faces(f, i), faces(f, (i + 1) % 3)}];
  }
  for (const auto& [edge, count] : directed) {
    ASSERT_EQ(count, 1);
    ASSERT_EQ(directed.count({edge.second, edge.first}), 1u);
  }
  // Three regions, ten rib pairs, symmetric about the midline.
  for (int region : {kSternumRegion, kRibRegion, kCartilageRegion})
    EXPECT_GT((g.regions.array() == region).count(), 100);
  EXPECT_EQ(g.tet_parts.maxCoeff(), 10);
  EXPECT_EQ(g.tet_parts.minCoeff(), -10);
  EXPECT_NEAR(g.nodes.col(0).maxCoeff(), -g.nodes.col(0).minCoeff(), 1e-9);
  // Element quality: Kuhn tetrahedra of the swept blocks stay well shaped.
  const Eigen::VectorXd q = RadiusRatios(mesh);
  EXPECT_GT(q.minCoeff(), 0.05);
  EXPECT_GT(q.mean(), 0.4);
  // Rib heads clamp: 2 x 10 faces of (2+1) x (2+1) corner nodes.
  EXPECT_EQ(g.fixed_nodes.size(), 20u * 9u);
  // The sternal notch is the origin, the xiphoid tip 153 mm below it.
  EXPECT_LT(g.nodes.row(g.landmarks.sternal_notch).norm(), 1e-9);
  EXPECT_NEAR(-g.nodes(g.landmarks.xiphoid_tip, 2), 153.0, 1e-9);
}

TEST(GenericRibcage, MeasuresAsAFlatAverageChest) {
  const GenericRibcage g = BuildGenericRibcage();
  RibcageSurface s;
  Eigen::VectorXi face_tet;
  s.nodes = g.nodes;
  s.faces = ExtractLinearBoundary(g.tets, &face_tet);
  s.face_parts.resize(face_tet.size());
  for (Eigen::Index f = 0; f < face_tet.size(); ++f) s.face_parts(f) = g.tet_parts(face_tet(f));
  s.spine_anterior = g.spine_anterior;
  const RibcageMeasurements m = MeasureRibcage(s);
  // The generic ribcage is normal: no depression, no torsion; close to the patients' mean proportions
  // (width 252, depth 142 mm); a Haller index in the normal range (under 3.25).
  EXPECT_LT(m.depression_mm, 0.05);
  EXPECT_NEAR(m.torsion_deg, 0.0, 0.05);
  EXPECT_NEAR(m.width_mm, 252.0, 15.0);
  EXPECT_NEAR(m.depth_mm, 142.0, 10.0);
  // Sternal length: the notch (anterior) to the posterior edge of the 4 mm thick, 20 degree tilted tip.
  EXPECT_NEAR(m.sternal_length_mm, 153.0 + 4.0 * std::sin(20.0 * M_PI / 180), 1e-6);
  EXPECT_GT(m.haller_index, 2.0);
  EXPECT_LT(m.haller_index, 3.25);
}

// Every rib cell length the planner accepts (2 to 20 mm) meshes without a folded tetrahedron (10 mm folded
// ribs 9-10 at their joint with the cartilage above, 2.6 mm folded rib 1 at the sternum, before the
// cartilages kept their own 4-6 mm cells), and the cartilages' cells do stay 4 to 6 mm: the cartilage's
// share of the mesh is the same at every rib cell length from 6 mm up, and from 4 mm down.
TEST(GenericRibcage, EveryRibCellLengthFromTwoToTwentyMillimetresMeshesWithoutFolds) {
  auto cartilage_tets = [](double cell_mm, int along) {
    GenericRibcageOptions o;
    o.rib_cell_length_mm = cell_mm;
    o.sternum_cells_along = along;
    const GenericRibcage g = BuildGenericRibcage(o);  // throws Error naming the part if a tetrahedron folds
    return (g.regions.array() == kCartilageRegion).count();
  };
  for (int along : {28, 34}) {
    const Eigen::Index at_6 = cartilage_tets(6.0, along), at_4 = cartilage_tets(4.0, along);
    EXPECT_GT(at_4, at_6 * 13 / 10) << along;  // 6 mm / 4 mm = 1.5 times as many cells, less the rounding
    for (double cell = 2.0; cell <= 20.0; cell += 0.5) {
      SCOPED_TRACE("rib cells " + std::to_string(cell) + " mm, sternum cells " + std::to_string(along));
      const Eigen::Index n = cartilage_tets(cell, along);
      if (cell >= 6.0) {
        EXPECT_EQ(n, at_6);
      }
      if (cell <= 4.0) {
        EXPECT_EQ(n, at_4);
      }
    }
  }
}

TEST(GenericRibcage, RejectsOptionsThatCannotBeMeshed) {
  GenericRibcageOptions o;
  o.rib_pairs = 12;
  EXPECT_THROW(BuildGenericRibcage(o), Error);
  o = {};
  o.sternum_cells_along = 16;  // the sternal joints of the lower ribs would touch
  EXPECT_THROW(BuildGenericRibcage(o), Error);
  o = {};
  o.sternum_cells_across = 3;  // no midline node
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_FALSE(why.empty());
}

}  // namespace
}  // namespace pectus::planner
