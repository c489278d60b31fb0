// The Nuss trainer's figures (docs/benchmarks.md, "The Nuss trainer"): the servo tick's cost over the full
// scene, the 1 kHz loop's periods, the inertial tracking's error and the drift of position integrated from
// the accelerations, the ArUco pose error, and the pictures of docs/trainer.md.
//   trainer_benchmark [--patient 57] [--loop-seconds 60] [--spin-us 200] [--realtime-priority 0]
//                     [--loop-only] [--pictures DIR]
// --loop-only measures the servo loop alone (for a run on an idle machine, kept short).
// Prints one JSON object. Exit code 3 if the shared patient table is missing.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "planner_plugin/host/scope_marker_pose.h"
#include "planner_plugin/ribcage/build_generic_ribcage.h"
#include "planner_plugin/ribcage/patient_ribcage.h"
#include "planner_plugin/trainer/god_object.h"
#include "planner_plugin/trainer/imu_orientation_filter.h"
#include "planner_plugin/trainer/scripted_paths.h"
#include "planner_plugin/trainer/servo_loop.h"
#include "planner_plugin/trainer/session_score.h"
#include "planner_plugin/trainer/thoracoscope.h"
#include "planner_plugin/trainer/trainer_session.h"
#include "shape/core/error.h"
#include "shape/core/sample_statistics.h"
#include "shape/io/patient_table_io.h"
#include "shape/render/image.h"
#include "shape/render/mesh_render.h"
#include "tests/planner_plugin/host/marker_poses.h"
#include "tests/planner_plugin/trainer/synthetic_imu.h"
#include "tests/support/shared_data.h"

namespace {

using namespace pectus;
using namespace pectus::trainer;
using Clock = std::chrono::steady_clock;

// Per-tick cost of the proxy (tip and shaft) replaying scripted sessions, microseconds.
nlohmann::json TickCost(const TrainerScene& scene) {
  nlohmann::json out;
  for (const Introducer& size : IntroducerSizes()) {
    std::vector<double> us;
    for (PathKind kind : {PathKind::kExpert, PathKind::kOntoPericardium, PathKind::kWrongSpace}) {
      ScriptedPathOptions o;
      o.kind = kind;
      SimulatedHand hand(MakeScriptedPath(scene, o));
      const SessionRecord r = RunSession(scene, &hand, size, {}, hand.target().duration_s());
      GodObject proxy(scene, size);
      proxy.Reset(r.samples.front().device_mm);
      for (const SessionSample& s : r.samples) {
        const auto t0 = Clock::now();
        proxy.Update(s.device_mm, s.orientation, r.period_s);
        us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
      }
    }
    out[size.name] = {{"ticks", us.size()},
                      {"mean_us", Mean(us)},
                      {"p50_us", Quantile(us, 0.5)},
                      {"p99_us", Quantile(us, 0.99)},
                      {"max_us", Max(us)}};
  }
  return out;
}

// The servo loop on its thread for `seconds`, each tick a proxy update replaying an expert's session.
nlohmann::json LoopPeriods(const TrainerScene& scene, double seconds, const ServoLoopOptions& options) {
  ScriptedPathOptions o;
  SimulatedHand hand(MakeScriptedPath(scene, o));
  const SessionRecord r = RunSession(scene, &hand, IntroducerSizes()[1], {}, hand.target().duration_s());
  GodObject proxy(scene, IntroducerSizes()[1]);
  proxy.Reset(r.samples.front().device_mm);
  std::size_t k = 0;
  ServoLoop loop(options);
  loop.Start([&](double) {
    const SessionSample& s = r.samples[k++ % r.samples.size()];
    proxy.Update(s.device_mm, s.orientation, 0.001);
  });
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  loop.Stop();
  const ServoLoopStatistics st = loop.Statistics();
  return {{"seconds", seconds},
          {"ticks", st.ticks},
          {"period_mean_ms", st.period_mean_ms},
          {"period_p50_ms", st.period_p50_ms},
          {"period_p99_ms", st.period_p99_ms},
          {"period_max_ms", st.period_max_ms},
          {"tick_p99_us", st.tick_p99_us},
          {"late_ticks", st.late_ticks},
          {"spin_us", options.spin_us},
          {"realtime_priority_asked", options.realtime_priority},
          {"sched_fifo", st.realtime},
          {"brief", st.BriefReport()}};
}

// The Madgwick filter on 5 min of synthetic scope motion (10 seeds, the gyro's bias wandering): the MARG
// form (the magnetometer holding the heading, the bias followed on-line) against the IMU form (gravity
// only) on the same data, and the position integrated from the accelerations (Eq. 16) with the MARG
// form's orientation and with the true one.
nlohmann::json Inertial() {
  nlohmann::json out = nlohmann::json::array();
  for (unsigned seed = 1; seed <= 10; ++seed) {
    testing::SyntheticImuOptions o;
    o.seed = seed;
    const testing::SyntheticImu imu = testing::MakeSyntheticImu(o);
    nlohmann::json row = {{"seed", seed}};
    for (const bool marg : {true, false}) {
      const auto t0 = Clock::now();
      const std::vector<Eigen::Quaterniond> q = testing::TrackOrientation(imu, o, {}, marg);
      const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
      double sum_sq = 0, worst = 0;
      for (std::size_t k = 1; k < q.size(); ++k) {
        const double e = testing::AngleDeg(q[k], imu.truth[k]);
        sum_sq += e * e;
        worst = std::max(worst, e);
      }
      row[marg ? "marg" : "imu"] = {
          {"orientation_rms_deg", std::sqrt(sum_sq / static_cast<double>(q.size() - 1))},
          {"orientation_worst_deg", worst},
          {"us_per_sample", 1e6 * seconds / static_cast<double>(q.size())}};
      if (!marg) continue;
      // Eq. 16 from the end of the still interval: x += v dt + a dt^2 / 2, v += a dt, a = R f - g.
      Eigen::Vector3d x_filter = Eigen::Vector3d::Zero(), v_filter = Eigen::Vector3d::Zero();
      Eigen::Vector3d x_truth_rot = Eigen::Vector3d::Zero(), v_truth_rot = Eigen::Vector3d::Zero();
      Eigen::Vector3d x_true = Eigen::Vector3d::Zero(), v_true = Eigen::Vector3d::Zero();
      nlohmann::json drift;
      const Eigen::Vector3d g(0, 0, 9.80665);
      for (std::size_t k = 1; k < imu.time_s.size(); ++k) {
        if (imu.time_s[k] <= o.still_s) continue;
        const double dt = imu.time_s[k] - imu.time_s[k - 1];
        const Eigen::Vector3d a_f = q[k] * imu.accel_m_s2[k] - g;
        const Eigen::Vector3d a_t = imu.truth[k] * imu.accel_m_s2[k] - g;
        const Eigen::Vector3d a_true = imu.true_accel_world_m_s2[k];
        x_filter += v_filter * dt + 0.5 * a_f * dt * dt, v_filter += a_f * dt;
        x_truth_rot += v_truth_rot * dt + 0.5 * a_t * dt * dt, v_truth_rot += a_t * dt;
        x_true += v_true * dt + 0.5 * a_true * dt * dt, v_true += a_true * dt;
        const double since = imu.time_s[k] - o.still_s;
        for (double mark : {1.0, 10.0, 60.0, 280.0}) {
          if (std::abs(since - mark) < 0.5 * dt) {
            drift[std::to_string(static_cast<int>(mark)) + "s"] = {
                {"with_filter_orientation_m", (x_filter - x_true).norm()},
                {"with_true_orientation_m", (x_truth_rot - x_true).norm()}};
          }
        }
      }
      row["position_drift_from_accelerations"] = drift;
    }
    out.push_back(row);
  }
  return out;
}

// The ArUco pose over the sweep, the rendered images as they are or with the camera's noise added
// (Gaussian, `noise_grey` grey levels, fixed seed).
nlohmann::json Markers(double noise_grey) {
  const MarkerCamera camera;
  const MarkerOptions options;
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, noise_grey);
  constexpr double kDeg = 3.14159265358979323846 / 180.0;  // for the errors
  std::vector<double> mm, deg;
  int missed = 0;
  for (double distance = 150; distance <= 350; distance += 25) {
    for (double tilt = 0; tilt <= 45; tilt += 7.5) {
      for (double spin : {0.0, 37.0, 81.0}) {
        const Eigen::Isometry3d T = testing::MarkerFacingCamera(distance, tilt, spin);
        GrayImage image = RenderMarkerView(camera, T, options);
        for (std::uint8_t& v : image.pixels) {
          if (noise_grey > 0)
            v = static_cast<std::uint8_t>(std::clamp(std::lround(v + noise(rng)), 0L, 255L));
        }
        const MarkerPoseResult r = EstimateMarkerPose(image, camera, options);
        if (!r.found) {
          ++missed;
          continue;
        }
        mm.push_back((r.T_camera_marker.translation() - T.translation()).norm());
        deg.push_back(Eigen::AngleAxisd(r.T_camera_marker.linear().transpose() * T.linear()).angle() / kDeg);
      }
    }
  }
  return {{"poses", mm.size() + static_cast<std::size_t>(missed)},
          {"missed", missed},
          {"position_mm", {{"median", Quantile(mm, 0.5)}, {"p95", Quantile(mm, 0.95)}, {"max", Max(mm)}}},
          {"rotation_deg", {{"median", Quantile(deg, 0.5)}, {"p95", Quantile(deg, 0.95)}, {"max", Max(deg)}}},
          {"noise_grey", noise_grey},
          {"setup", "50 mm marker (DICT_4X4_50 id 7), 150-350 mm, tilt 0-45 deg, 640 x 480, f 500 px"}};
}

// The scene's meshes in one coloured mesh (bones ivory, pericardium red, lungs blue, the tunnel green).
TriangleMesh SceneMesh(const TrainerScene& scene, bool with_tunnel) {
  TriangleMesh all;
  std::vector<std::pair<TriangleMesh, render::Rgb>> parts;
  TriangleMesh bone;
  bone.vertices.positions = scene.bone_vertices;
  bone.faces = scene.bone_faces;
  parts.push_back({bone, {225, 215, 190}});
  parts.push_back({scene.pericardium.mesh, {200, 60, 60}});
  parts.push_back({scene.right_lung.mesh, {120, 150, 210}});
  parts.push_back({scene.left_lung.mesh, {120, 150, 210}});
  for (Eigen::Index i = 0; with_tunnel && i < scene.tunnel.points.rows(); i += 2) {
    parts.push_back(
        {MakeEllipsoidMesh(scene.tunnel.points.row(i).transpose(), Eigen::Vector3d::Constant(1.8), 1),
         {40, 170, 60}});
  }
  Eigen::Index nv = 0, nf = 0;
  for (const auto& [m, c] : parts) nv += m.num_vertices(), nf += m.num_faces();
  all.vertices.positions.resize(nv, 3);
  all.vertices.colors.resize(nv, 3);
  all.faces.resize(nf, 3);
  Eigen::Index v0 = 0, f0 = 0;
  for (const auto& [m, c] : parts) {
    all.vertices.positions.middleRows(v0, m.num_vertices()) = m.vertices.positions;
    for (Eigen::Index i = 0; i < m.num_vertices(); ++i) all.vertices.colors.row(v0 + i) << c.r, c.g, c.b;
    all.faces.middleRows(f0, m.num_faces()) = m.faces.array() + static_cast<std::int32_t>(v0);
    v0 += m.num_vertices();
    f0 += m.num_faces();
  }
  return all;
}

void Pictures(const TrainerScene& scene, const std::string& dir) {
  const TriangleMesh mesh = SceneMesh(scene, true);
  // The pectus frame is LPS: the front view looks along +y (from anterior), up is +z.
  render::View front;
  front.direction = {0, 1, 0};
  front.up = {0, 0, 1};
  front.width = 800;
  front.height = 700;
  render::View top = front;
  top.direction = {0, 0, -1};
  top.up = {0, -1, 0};
  Bounds3 slab;
  slab.min = {-160, -120, scene.tunnel.level_z_mm - 25};
  slab.max = {160, 160, scene.tunnel.level_z_mm + 25};
  TriangleMesh cut = mesh;  // the slab around the bar's level, from above
  std::vector<Eigen::Index> keep;
  for (Eigen::Index f = 0; f < mesh.num_faces(); ++f) {
    bool in = true;
    for (int i = 0; i < 3; ++i) {
      const double z = mesh.vertices.positions(mesh.faces(f, i), 2);
      in = in && z <= slab.max.z() && z >= slab.min.z();
    }
    if (in) keep.push_back(f);
  }
  cut.faces.resize(static_cast<Eigen::Index>(keep.size()), 3);
  for (std::size_t i = 0; i < keep.size(); ++i)
    cut.faces.row(static_cast<Eigen::Index>(i)) = mesh.faces.row(keep[i]);
  top.frame = slab;
  render::WritePng(render::HStack({render::WithTitle(render::RenderMesh(mesh, front), "front"),
                                   render::WithTitle(render::RenderMesh(cut, top),
                                                     "from above, the bar's level +- 25 mm")},
                                  8),
                   dir + "/trainer_scene.png");
  // The scope's view: the scope in the right chest, one space below the entry, looking at the middle of
  // the tunnel; perspective by projecting the vertices (x/z, y/z) and drawing orthographically.
  const ScopeCamera camera;
  ScopePose pose;
  pose.port_mm = scene.tunnel.entry_port + Eigen::Vector3d(0, 0, -30);
  Eigen::Index mid = 0;
  scene.tunnel.points.col(0).cwiseAbs().minCoeff(&mid);
  const Eigen::Vector3d target = scene.tunnel.points.row(mid).transpose();
  // Aim the oblique view (30 degrees off the axis) at the target: the axis turned back by the oblique.
  const Eigen::Vector3d view = (target - pose.port_mm).normalized();
  pose.orientation = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), view);
  pose.orientation = pose.orientation * Eigen::Quaterniond(camera.ScopeFromCamera().transpose());
  pose.insertion_mm = 30;
  const TriangleMesh inside = SceneMesh(scene, true);
  TriangleMesh projected = inside;
  const Eigen::Isometry3d camera_from_scene = camera.SceneFromCamera(pose).inverse();
  std::vector<Eigen::Index> visible;
  for (Eigen::Index i = 0; i < inside.num_vertices(); ++i) {
    const Eigen::Vector3d p =
        camera_from_scene * Eigen::Vector3d(inside.vertices.positions.row(i).transpose());
    projected.vertices.positions.row(i) << p.x() / std::max(p.z(), 1e-3), p.y() / std::max(p.z(), 1e-3),
        p.z();
  }
  for (Eigen::Index f = 0; f < inside.num_faces(); ++f) {
    bool in_front = true;
    for (int i = 0; i < 3; ++i)
      in_front = in_front && projected.vertices.positions(inside.faces(f, i), 2) > 2.0;
    if (in_front) visible.push_back(f);
  }
  projected.faces.resize(static_cast<Eigen::Index>(visible.size()), 3);
  for (std::size_t i = 0; i < visible.size(); ++i)
    projected.faces.row(static_cast<Eigen::Index>(i)) = inside.faces.row(visible[i]);
  render::View scope;
  scope.direction = {0, 0, 1};
  scope.up = {0, -1, 0};
  scope.width = camera.options().width_px;
  scope.height = camera.options().height_px;
  scope.margin = 0;
  const double tx = 0.5 * camera.options().width_px / camera.focal_px();
  const double ty = 0.5 * camera.options().height_px / camera.focal_px();
  Bounds3 ndc;
  ndc.min = {-tx, -ty, 0};
  ndc.max = {tx, ty, 400};
  scope.frame = ndc;
  scope.background = {20, 20, 20};
  render::WritePng(
      render::WithTitle(render::RenderMesh(projected, scope), "scope: 30 deg oblique, 80 deg field"),
      dir + "/trainer_scope_view.png");
}

}  // namespace

int main(int argc, char** argv) {
  int patient = 57;
  double loop_seconds = 60;
  std::string pictures;
  ServoLoopOptions loop_options;
  bool loop_only = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--patient" && i + 1 < argc)
      patient = std::stoi(argv[++i]);
    else if (a == "--loop-seconds" && i + 1 < argc)
      loop_seconds = std::stod(argv[++i]);
    else if (a == "--spin-us" && i + 1 < argc)
      loop_options.spin_us = std::stod(argv[++i]);
    else if (a == "--realtime-priority" && i + 1 < argc)
      loop_options.realtime_priority = std::stoi(argv[++i]);
    else if (a == "--loop-only")
      loop_only = true;
    else if (a == "--pictures" && i + 1 < argc)
      pictures = argv[++i];
    else {
      std::cerr << "usage: trainer_benchmark [--patient N] [--loop-seconds S] [--spin-us US] "
                   "[--realtime-priority P] [--loop-only] [--pictures DIR]\n";
      return 2;
    }
  }
  if (!testing_support::HaveSharedFile("trainer_benchmark", testing_support::kPatientTable)) return 3;
  try {
    nlohmann::json report;
    const std::string table = testing_support::SharedPath(testing_support::kPatientTable);
    const auto rows = ReadPatientTable(table);
    auto t0 = Clock::now();
    const planner::GenericRibcage generic = planner::BuildGenericRibcage();
    const planner::PatientRibcage ribcage =
        planner::MakePatientRibcage(generic, planner::MeasurementsOf(FindPatient(rows, patient, table)));
    const TrainerScene scene = BuildTrainerScene(ribcage);
    report["scene"] = {{"patient", patient},
                       {"seconds", std::chrono::duration<double>(Clock::now() - t0).count()},
                       {"collision_triangles", scene.collision_faces.rows()},
                       {"bone_triangles", scene.bone_faces.rows()},
                       {"tunnel_mm", scene.tunnel.length_mm},
                       {"entry", scene.tunnel.entry.Name()},
                       {"exit", scene.tunnel.exit.Name()}};
    if (!loop_only) {
      report["tick_cost"] = TickCost(scene);
      report["inertial"] = Inertial();
      report["markers"] = Markers(0);
      report["markers_noisy"] = Markers(2);
      if (!pictures.empty()) Pictures(scene, pictures);
    }
    if (loop_seconds > 0) report["servo_loop"] = LoopPeriods(scene, loop_seconds, loop_options);
    std::cout << report.dump(2) << "\n";
  } catch (const Error& e) {
    std::cerr << "trainer_benchmark: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
