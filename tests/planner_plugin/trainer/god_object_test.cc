#include "planner_plugin/trainer/god_object.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <utility>
#include <vector>

#include "planner_plugin/trainer/haptic_device.h"
#include "planner_plugin/trainer/trainer_session.h"
#include "tests/planner_plugin/trainer/trainer_test_scene.h"
#include "tests/support/require_shared_data.h"

namespace pectus::trainer {
namespace {

// A scene of closed boxes (lo, hi corners, mm) of `organ`.
TrainerScene BoxScene(Organ organ, const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>>& boxes = {
                                       {{-20, -20, -20}, {20, 20, 0}}}) {
  TrainerScene s;
  Points3 v(8 * static_cast<Eigen::Index>(boxes.size()), 3);
  Faces3 f(12 * static_cast<Eigen::Index>(boxes.size()), 3);
  Faces3 one(12, 3);
  one << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3,
      7, 5;
  for (std::size_t b = 0; b < boxes.size(); ++b) {
    const auto& [lo, hi] = boxes[b];
    const auto k = static_cast<Eigen::Index>(b);
    for (int i = 0; i < 8; ++i)
      v.row(8 * k + i) << (i & 1 ? hi : lo).x(), (i & 2 ? hi : lo).y(), (i & 4 ? hi : lo).z();
    f.middleRows(12 * k, 12) = one.array() + static_cast<std::int32_t>(8 * k);
  }
  s.collision_vertices = v;
  s.collision_faces = f;
  s.collision_organ = Eigen::VectorXi::Constant(f.rows(), organ);
  s.collision = TriangleGrid(v, f, 6.0);
  return s;
}

TEST(GodObject, ProxyStaysOnTheSurfaceAndTheSpringPushesBackWithTheTissuesStiffness) {
  const TrainerScene box = BoxScene(kBone);
  ProxyOptions options;
  options.damping_n_s_per_mm = 0;         // the spring alone
  options.shaft_collision_length_mm = 0;  // the tip alone
  options.force_shading = false;          // a box's corner normals are not its faces'
  options.max_force_n = 100;              // no clamping
  GodObject proxy(box, IntroducerSizes()[1], options);
  const Eigen::Quaterniond up =
      Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), -Eigen::Vector3d::UnitZ());
  proxy.Reset({1, 2, 10});
  proxy.Update({1, 2, 5}, up, 0.001);  // free: the proxy is the tip
  EXPECT_EQ(proxy.contact().num_planes, 0);
  EXPECT_TRUE(proxy.contact().force_n.isZero());
  const ProxyContact& c = proxy.Update({1, 2, -2}, up, 0.001);  // 2 mm into the top face
  ASSERT_EQ(c.num_planes, 1);
  EXPECT_NEAR(c.proxy_mm.z(), options.surface_offset_mm, 1e-12);
  EXPECT_NEAR(c.proxy_mm.x(), 1, 1e-9);
  // F = -k x (Eq. 15): 2.0 N/mm over 2 mm (plus the offset), straight up.
  EXPECT_NEAR(c.force_n.z(), options.stiffness_n_per_mm[kBone] * (2 + options.surface_offset_mm), 1e-9);
  EXPECT_NEAR(c.force_n.head<2>().norm(), 0, 1e-9);
  // Static friction: a sideways pull within 0.3 of the depth keeps the proxy where it was.
  const ProxyContact& held = proxy.Update({1.5, 2, -2}, up, 0.001);
  EXPECT_TRUE(held.stuck);
  EXPECT_NEAR(held.proxy_mm.x(), 1, 1e-9);
  EXPECT_NEAR(held.force_n.x(), -options.stiffness_n_per_mm[kBone] * 0.5, 1e-9);
  // Beyond the cone it slides, lagging the tip by the dynamic friction's share of the depth.
  const ProxyContact& slid = proxy.Update({5, 2, -2}, up, 0.001);
  EXPECT_FALSE(slid.stuck);
  EXPECT_NEAR(5 - slid.proxy_mm.x(), options.dynamic_friction * (2 + options.surface_offset_mm), 1e-6);
  // Into a concave corner (a wall standing on the floor): two planes hold the proxy in the corner's edge.
  const TrainerScene corner_scene =
      BoxScene(kBone, {{{-20, -20, -20}, {20, 20, 0}}, {{10, -20, 0}, {20, 20, 20}}});
  GodObject in_corner(corner_scene, IntroducerSizes()[1], options);
  in_corner.Reset({0, 0, 5});
  const ProxyContact& corner = in_corner.Update({15, 0, -3}, up, 0.001);
  EXPECT_EQ(corner.num_planes, 2);
  EXPECT_NEAR(corner.proxy_mm.x(), 10 - options.surface_offset_mm, 1e-9);
  EXPECT_NEAR(corner.proxy_mm.z(), options.surface_offset_mm, 1e-9);
  EXPECT_NEAR(corner.force_n.x(), -options.stiffness_n_per_mm[kBone] * (5 + options.surface_offset_mm), 1e-9);
  // A bad reading (NaN) renders nothing and keeps the proxy.
  const Eigen::Vector3d kept = in_corner.contact().proxy_mm;
  const ProxyContact& bad = in_corner.Update(Eigen::Vector3d::Constant(std::nan("")), up, 0.001);
  EXPECT_TRUE(bad.force_n.isZero());
  EXPECT_EQ(bad.proxy_mm, kept);
  // A softer tissue pushes back with its own stiffness.
  const TrainerScene soft = BoxScene(kPericardium);
  GodObject on_heart(soft, IntroducerSizes()[1], options);
  on_heart.Reset({0, 0, 5});
  const ProxyContact& h = on_heart.Update({0, 0, -3}, up, 0.001);
  EXPECT_NEAR(h.force_n.z(), options.stiffness_n_per_mm[kPericardium] * (3 + options.surface_offset_mm),
              1e-9);
  EXPECT_NE(h.organs_touched & (1u << kPericardium), 0u);
}

TEST(GodObject, ShaftCollidesAsACapsuleOfTheIntroducersRadius) {
  const TrainerScene box = BoxScene(kBone);
  for (const Introducer& size : IntroducerSizes()) {
    ProxyOptions unlimited;
    unlimited.max_force_n = 1000;
    unlimited.shaft_collision_length_mm = 36;
    GodObject proxy(box, size, unlimited);
    // The tip above the box, the shaft lying along x 1 mm above the top face: it touches the box only if
    // its radius exceeds 1 mm, pushed up by k (r - 1).
    const Eigen::Quaterniond along_x =
        Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX());
    proxy.Reset({18, 0, 1});
    const ProxyContact& c = proxy.Update({18, 0, 1}, along_x, 0.001);
    const double r = 0.5 * size.diameter_mm;
    EXPECT_GT(c.force_n.z(), 0) << size.name;
    // Nine samples 4 mm apart behind the tip, all over the box, each pressing k (r - 1).
    EXPECT_NEAR(c.force_n.z(), 9 * 2.0 * (r - 1), 1e-9) << size.name;
  }
}

// Energy the environment gives the device over press-release cycles: sum F_k . (x_k+1 - x_k).
double EnergyGiven(const SessionRecord& r) {
  double w = 0;
  for (std::size_t k = 0; k + 1 < r.samples.size(); ++k) {
    w += r.samples[k].force_n.dot(r.samples[k + 1].device_mm - r.samples[k].device_mm);
  }
  return w;
}

TEST(GodObject, PressAndReleaseCyclesGainNoEnergy) {
  PECTUS_REQUIRE_SHARED_FILE(testing_support::kPatientTable);
  const TrainerScene& scene = testing::SceneOf(57);
  // The hand presses 6 mm into the sternum's front (bone) and the pericardium, three times each.
  const Eigen::Vector3d sternum_front(0, scene.sternum_back_y_mm - 30, scene.tunnel.level_z_mm + 20);
  std::vector<SurfaceHit> hits;
  scene.collision.AllHits(sternum_front, sternum_front + Eigen::Vector3d(0, 200, 0), &hits);
  ASSERT_FALSE(hits.empty());
  const Eigen::Vector3d bone = hits.front().point;
  hits.clear();
  const Eigen::Vector3d heart_in = scene.pericardium.centre;
  const Eigen::Vector3d heart_out = heart_in + Eigen::Vector3d(0, 0, 3 * scene.pericardium.semi_axes.z());
  scene.collision.AllHits(heart_out, heart_in, &hits);
  ASSERT_FALSE(hits.empty());
  const Eigen::Vector3d heart = hits.front().point;
  for (const auto& [surface, inward] :
       {std::pair{bone, Eigen::Vector3d(0, 1, 0)}, std::pair{heart, Eigen::Vector3d(0, 0, -1)}}) {
    Trajectory target;
    for (int k = 0; k <= 300; ++k) {  // 3 cycles of 1 s, 10 ms samples: from 5 mm outside to 6 mm inside
      DeviceState s;
      s.time_s = 0.01 * k;
      const double phase = 0.5 - 0.5 * std::cos(2 * 3.14159265358979 * s.time_s);
      s.position_mm = surface + (-5 + 11 * phase) * inward;
      s.orientation = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), inward);
      target.samples.push_back(s);
    }
    SimulatedHand hand(target);
    const SessionRecord r = RunSession(scene, &hand, IntroducerSizes()[1], {}, 3.0);
    const double peak = [&] {
      double m = 0;
      for (const SessionSample& s : r.samples) m = std::max(m, s.force_n.norm());
      return m;
    }();
    const double w = EnergyGiven(r);
    std::printf("press-release at (%.0f, %.0f, %.0f): peak %.2f N, energy given to the hand %.3g N mm\n",
                surface.x(), surface.y(), surface.z(), peak, w);
    EXPECT_GT(peak, 0.5);
    EXPECT_LE(w, 0.0);
  }
}

}  // namespace
}  // namespace pectus::trainer
