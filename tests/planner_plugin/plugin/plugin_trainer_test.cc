// The trainer through the plugin's C boundary (interface version 5): a session ticked through it is the
// engine's own session bit for bit; its record replays to the same scores; the plugin's servo thread ticks
// the host's device; the thoracoscope's aimed view looks at its target; bad calls come back as statuses.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>

#include "planner_plugin/plugin/planner_session.h"
#include "planner_plugin/trainer/haptic_device.h"
#include "planner_plugin/trainer/scripted_paths.h"
#include "planner_plugin/trainer/session_score.h"
#include "planner_plugin/trainer/thoracoscope.h"
#include "planner_plugin/trainer/trainer_scene.h"
#include "planner_plugin/trainer/trainer_session.h"
#include "tests/planner_plugin/plugin/plugin_fixture.h"
#include "tests/support/require_shared_data.h"

namespace {

namespace fs = std::filesystem;
using namespace pectus::trainer;

class PluginTrainer : public pectus::testing_support::PluginTest {
 protected:
  static void SetUpTestSuite() {
    PluginTest::SetUpTestSuite();
    if (!fs::exists(pectus::testing_support::PatientTablePath())) return;
    PectusPlannerStatus status{};
    ASSERT_EQ(
        api_->read_patient(pectus::testing_support::PatientTablePath().c_str(), "57", &patient_, &status),
        PECTUS_PLANNER_OK)
        << status.message;
    options_ = Coarse();
    ASSERT_EQ(api_->create(&patient_, &options_, &planner_, &status), PECTUS_PLANNER_OK) << status.message;
    // The same patient's scene made by the engine in this process, as the plugin makes it.
    const pectus::planner::PlannerSettings settings = pectus::planner::SettingsFrom(&options_);
    scene_ = std::make_unique<TrainerScene>(BuildTrainerScene(
        pectus::planner::MakePatientRibcage(pectus::planner::BuildGenericRibcage(settings.generic),
                                            pectus::planner::MeasurementsFrom(patient_), settings.patient)));
  }
  static void TearDownTestSuite() {
    api_->destroy(planner_);
    planner_ = nullptr;
    scene_.reset();
    PluginTest::TearDownTestSuite();
  }
  void SetUp() override { PECTUS_REQUIRE_SHARED_FILE(pectus::testing_support::kPatientTable); }

  static PectusPlannerDeviceState StateOf(const DeviceState& d, double time_s) {
    PectusPlannerDeviceState s{};
    s.time_s = time_s;
    for (int k = 0; k < 3; ++k) s.position_mm[k] = d.position_mm[k];
    s.orientation_wxyz[0] = d.orientation.w();
    s.orientation_wxyz[1] = d.orientation.x();
    s.orientation_wxyz[2] = d.orientation.y();
    s.orientation_wxyz[3] = d.orientation.z();
    s.buttons = d.buttons;
    return s;
  }

  static PectusPlannerPatient patient_;
  static PectusPlannerOptions options_;
  static PectusPlanner* planner_;
  static std::unique_ptr<TrainerScene> scene_;
};
std::unique_ptr<TrainerScene> PluginTrainer::scene_;
PectusPlannerPatient PluginTrainer::patient_{};
PectusPlannerOptions PluginTrainer::options_{};
PectusPlanner* PluginTrainer::planner_ = nullptr;

TEST_F(PluginTrainer, ASessionTickedThroughTheBoundaryIsTheEnginesSessionBitForBitAndReplaysToItsScores) {
  const TrainerScene& scene = *scene_;
  ScriptedPathOptions path;
  path.kind = PathKind::kOntoPericardium;  // contacts, friction and the shaft: every part of a tick
  const Trajectory target = MakeScriptedPath(scene, path);
  const double period = 0.001;
  ScriptedDevice device(target);
  const SessionRecord engine =
      RunSession(scene, &device, IntroducerNamed("medium"), ProxyOptions{}, target.duration_s(), period);

  PectusPlannerStatus status{};
  PectusPlannerTrainer* trainer = nullptr;
  ASSERT_EQ(api_->trainer_create(planner_, "medium", 0, &trainer, &status), PECTUS_PLANNER_OK)
      << status.message;
  // The scene the host draws is the engine's.
  PectusPlannerMesh pericardium{};
  ASSERT_EQ(api_->trainer_mesh(trainer, 1, &pericardium, &status), PECTUS_PLANNER_OK);
  ASSERT_EQ(pericardium.num_vertices, scene.pericardium.mesh.num_vertices());
  EXPECT_EQ(std::memcmp(pericardium.vertices, scene.pericardium.mesh.vertices.positions.data(),
                        sizeof(double) * 3 * pericardium.num_vertices),
            0);
  PectusPlannerTunnel tunnel{};
  std::vector<double> points(3 * static_cast<std::size_t>(scene.tunnel.points.rows()));
  ASSERT_EQ(api_->trainer_tunnel(trainer, &tunnel, points.data(), scene.tunnel.points.rows(), &status),
            PECTUS_PLANNER_OK)
      << status.message;
  EXPECT_EQ(tunnel.entry.number, scene.tunnel.entry.number);
  EXPECT_EQ(tunnel.exit.side, +1);
  EXPECT_EQ(points.back(), scene.tunnel.points(scene.tunnel.points.rows() - 1, 2));
  // The scope's port is a right space below (or above) the entry, on the chest wall.
  EXPECT_LT(tunnel.scope_port_mm[0], 0);
  EXPECT_GT(std::hypot(tunnel.scope_port_mm[0] - tunnel.entry_port_mm[0],
                       tunnel.scope_port_mm[2] - tunnel.entry_port_mm[2]),
            5.0);

  PectusPlannerTrainerTick tick{};
  for (std::size_t k = 0; k < engine.samples.size(); ++k) {
    const double t = engine.samples[k].time_s;
    const PectusPlannerDeviceState s = StateOf(target.At(t), t);
    ASSERT_EQ(api_->trainer_tick(trainer, &s, &tick, &status), PECTUS_PLANNER_OK) << status.message;
    const SessionSample& e = engine.samples[k];
    ASSERT_EQ(tick.tick, static_cast<std::int64_t>(k + 1));
    for (int i = 0; i < 3; ++i) {
      ASSERT_EQ(tick.proxy_mm[i], e.proxy_mm[i]) << "tick " << k;
      ASSERT_EQ(tick.force_n[i], e.force_n[i]) << "tick " << k;
    }
    ASSERT_EQ(tick.organs_touched, e.organs_touched) << "tick " << k;
    ASSERT_EQ(tick.pericardium_force_n, e.pericardium_force_n);
    ASSERT_EQ(tick.pericardium_distance_mm, scene.DistanceToPericardium(e.proxy_mm));
  }
  const SessionScore expected = ScoreSession(scene, engine);
  EXPECT_GE(expected.pericardial_contacts, 1);  // the path does what it is named for
  PectusPlannerTrainerScore score{};
  ASSERT_EQ(api_->trainer_score(trainer, &score, &status), PECTUS_PLANNER_OK) << status.message;
  EXPECT_EQ(score.ticks, static_cast<std::int64_t>(engine.samples.size()));
  EXPECT_EQ(score.score, expected.score);
  EXPECT_EQ(score.min_pericardium_distance_mm, expected.min_pericardium_distance_mm);
  EXPECT_EQ(score.pericardial_contacts, expected.pericardial_contacts);
  EXPECT_EQ(score.path_length_mm, expected.path_length_mm);
  EXPECT_EQ(score.rms_tunnel_deviation_mm, expected.rms_tunnel_deviation_mm);
  EXPECT_EQ(score.entry.number, expected.entry.number);
  EXPECT_EQ(score.exit_as_planned, expected.exit_as_planned ? 1 : 0);

  // The record, written and replayed through the boundary: the same scores to the bit.
  const fs::path dir = fs::path(::testing::TempDir()) / "plugin_trainer_record";
  fs::create_directories(dir);
  const std::string record = (dir / "session.txt").string();
  ASSERT_EQ(api_->trainer_write_record(trainer, record.c_str(), &status), PECTUS_PLANNER_OK)
      << status.message;
  PectusPlannerTrainerScore replayed{};
  ASSERT_EQ(api_->trainer_replay(trainer, record.c_str(), &replayed, &status), PECTUS_PLANNER_OK)
      << status.message;
  EXPECT_EQ(std::memcmp(&replayed, &score, sizeof(score)), 0);

  // Time going back, a non-finite state: refused, nothing ticked.
  PectusPlannerDeviceState back = StateOf(target.At(0), 0.0);
  EXPECT_EQ(api_->trainer_tick(trainer, &back, &tick, &status), PECTUS_PLANNER_USAGE);
  EXPECT_NE(std::string(status.message).find("time went back"), std::string::npos) << status.message;
  PectusPlannerDeviceState nan = StateOf(target.At(0), 1e3);
  nan.position_mm[1] = std::nan("");
  EXPECT_EQ(api_->trainer_tick(trainer, &nan, &tick, &status), PECTUS_PLANNER_USAGE);
  ASSERT_EQ(api_->trainer_score(trainer, &score, &status), PECTUS_PLANNER_OK);
  EXPECT_EQ(score.ticks, static_cast<std::int64_t>(engine.samples.size()));
  // A new session starts empty.
  ASSERT_EQ(api_->trainer_reset(trainer, &status), PECTUS_PLANNER_OK);
  EXPECT_EQ(api_->trainer_score(trainer, &score, &status), PECTUS_PLANNER_USAGE);
  EXPECT_EQ(api_->trainer_latest(trainer, &tick, &status), PECTUS_PLANNER_USAGE);
  api_->trainer_destroy(trainer);
  fs::remove_all(dir);
}

// The host's device for the servo thread: replays a trajectory and counts the forces it is sent.
struct ReplayingDevice {
  const Trajectory* target;
  std::atomic<int> reads{0}, forces{0};
  static void Read(void* user, double time_s, PectusPlannerDeviceState* out) {
    auto* d = static_cast<ReplayingDevice*>(user);
    const DeviceState s = d->target->At(time_s);
    for (int k = 0; k < 3; ++k) out->position_mm[k] = s.position_mm[k];
    out->orientation_wxyz[0] = s.orientation.w();
    out->orientation_wxyz[1] = s.orientation.x();
    out->orientation_wxyz[2] = s.orientation.y();
    out->orientation_wxyz[3] = s.orientation.z();
    d->reads.fetch_add(1);
  }
  static void SetForce(void* user, const double*, const double*) {
    static_cast<ReplayingDevice*>(user)->forces.fetch_add(1);
  }
};

TEST_F(PluginTrainer, ThePluginsServoThreadTicksTheHostsDeviceAndTheScopeLooksAtItsTargetWithTheHeadUp) {
  PectusPlannerStatus status{};
  PectusPlannerTrainer* trainer = nullptr;
  ASSERT_EQ(api_->trainer_create(planner_, "small", 0, &trainer, &status), PECTUS_PLANNER_OK)
      << status.message;
  const TrainerScene& scene = *scene_;
  const Trajectory target = MakeScriptedPath(scene, ScriptedPathOptions{});
  ReplayingDevice replaying{&target};
  const PectusPlannerDevice device{&replaying, &ReplayingDevice::Read, &ReplayingDevice::SetForce};
  ASSERT_EQ(api_->trainer_start(trainer, &device, 0, &status), PECTUS_PLANNER_OK) << status.message;
  // While it runs: one tick at a time from the host is refused, a new session too; the latest tick and the
  // score so far are read from this thread.
  PectusPlannerTrainerTick tick{};
  PectusPlannerDeviceState s = StateOf(target.At(0), 0);
  EXPECT_EQ(api_->trainer_tick(trainer, &s, &tick, &status), PECTUS_PLANNER_USAGE);
  EXPECT_EQ(api_->trainer_reset(trainer, &status), PECTUS_PLANNER_USAGE);
  std::int64_t last = 0;
  PectusPlannerTrainerScore score{};
  for (int i = 0; i < 20; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(15));
    if (api_->trainer_latest(trainer, &tick, &status) == PECTUS_PLANNER_OK) {
      EXPECT_GE(tick.tick, last);
      last = tick.tick;
    }
    if (tick.tick >= 2) {
      ASSERT_EQ(api_->trainer_score(trainer, &score, &status), PECTUS_PLANNER_OK) << status.message;
      EXPECT_GE(score.ticks, 2);
    }
  }
  PectusPlannerLoopStatistics loop{};
  ASSERT_EQ(api_->trainer_stop(trainer, &loop, &status), PECTUS_PLANNER_OK) << status.message;
  EXPECT_GT(loop.ticks, 50);  // 300 ms at 1 kHz, however loaded the machine
  EXPECT_EQ(replaying.reads.load(), loop.ticks);
  EXPECT_EQ(replaying.forces.load(), loop.ticks);
  ASSERT_EQ(api_->trainer_score(trainer, &score, &status), PECTUS_PLANNER_OK);
  EXPECT_EQ(score.ticks, loop.ticks);
  // Every recorded tick is where the engine puts the proxy for that device state (a replay of the record).
  const fs::path record = fs::path(::testing::TempDir()) / "plugin_trainer_servo.txt";
  ASSERT_EQ(api_->trainer_write_record(trainer, record.c_str(), &status), PECTUS_PLANNER_OK);
  PectusPlannerTrainerScore replayed{};
  ASSERT_EQ(api_->trainer_replay(trainer, record.c_str(), &replayed, &status), PECTUS_PLANNER_OK);
  EXPECT_EQ(replayed.score, score.score);
  EXPECT_EQ(replayed.path_length_mm, score.path_length_mm);
  fs::remove(record);
  // No tick yet after a reset: the scope has nothing to aim at by default.
  ASSERT_EQ(api_->trainer_reset(trainer, &status), PECTUS_PLANNER_OK);
  PectusPlannerScopeView none{};
  EXPECT_EQ(api_->trainer_scope_view(trainer, nullptr, nullptr, 30.0, &none, &status), PECTUS_PLANNER_USAGE);

  PectusPlannerTunnel tunnel{};
  ASSERT_EQ(api_->trainer_tunnel(trainer, &tunnel, nullptr, 0, &status), PECTUS_PLANNER_OK);
  const Eigen::Vector3d port(tunnel.scope_port_mm[0], tunnel.scope_port_mm[1], tunnel.scope_port_mm[2]);
  const ScopeCamera camera;
  // Targets across the chest: the exit port, the middle of the tunnel under the sternum.
  const Eigen::Index middle = scene_->tunnel.points.rows() / 2;
  const double under_sternum[3] = {scene_->tunnel.points(middle, 0), scene_->tunnel.points(middle, 1),
                                   scene_->tunnel.points(middle, 2)};
  for (const double* aim : {static_cast<const double*>(tunnel.exit_port_mm), under_sternum}) {
    PectusPlannerScopeView v{};
    ASSERT_EQ(api_->trainer_scope_view(trainer, nullptr, aim, 30.0, &v, &status), PECTUS_PLANNER_OK)
        << status.message;
    ScopePose pose;
    pose.orientation = Eigen::Quaterniond(v.orientation_wxyz[0], v.orientation_wxyz[1], v.orientation_wxyz[2],
                                          v.orientation_wxyz[3]);
    pose.port_mm = port;
    pose.insertion_mm = 30.0;
    // The eye is the scope's tip, and the target falls on the image's centre (the pinhole model's).
    EXPECT_LT((pose.Tip() - Eigen::Vector3d(v.eye_mm[0], v.eye_mm[1], v.eye_mm[2])).norm(), 1e-9);
    Eigen::Vector2d pixel;
    ASSERT_TRUE(camera.Project(pose, Eigen::Vector3d(aim[0], aim[1], aim[2]), &pixel));
    EXPECT_LT((pixel - camera.principal_point()).norm(), 1e-6) << pixel.transpose();
    // Up is square to the view and towards the head.
    const Eigen::Vector3d forward(v.forward[0], v.forward[1], v.forward[2]), up(v.up[0], v.up[1], v.up[2]);
    EXPECT_NEAR(forward.dot(up), 0.0, 1e-12);
    EXPECT_GT(up.z(), 0.0);
    EXPECT_NEAR(v.vertical_fov_deg, 2 * std::atan(0.75 * std::tan(40 * M_PI / 180)) * 180 / M_PI, 1e-9);
    // The same orientation given back gives the same view.
    PectusPlannerScopeView again{};
    ASSERT_EQ(api_->trainer_scope_view(trainer, v.orientation_wxyz, nullptr, 30.0, &again, &status),
              PECTUS_PLANNER_OK);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(again.forward[k], v.forward[k], 1e-12);
  }
  // A zero quaternion, an unknown part, an unknown introducer: statuses.
  PectusPlannerScopeView v{};
  const double zero[4] = {0, 0, 0, 0};
  EXPECT_EQ(api_->trainer_scope_view(trainer, zero, nullptr, 30.0, &v, &status), PECTUS_PLANNER_USAGE);
  PectusPlannerMesh mesh{};
  EXPECT_EQ(api_->trainer_mesh(trainer, 7, &mesh, &status), PECTUS_PLANNER_USAGE);
  EXPECT_NE(std::string(status.message).find("part 7"), std::string::npos);
  PectusPlannerTrainer* other = nullptr;
  EXPECT_EQ(api_->trainer_create(planner_, "huge", 0, &other, &status), PECTUS_PLANNER_BAD_INPUT);
  EXPECT_NE(std::string(status.message).find("huge"), std::string::npos) << status.message;
  EXPECT_EQ(other, nullptr);
  EXPECT_EQ(api_->trainer_replay(trainer, "/nonexistent/record.txt", &score, &status),
            PECTUS_PLANNER_BAD_INPUT);
  EXPECT_NE(std::string(status.message).find("/nonexistent/record.txt"), std::string::npos) << status.message;
  api_->trainer_destroy(trainer);
}

}  // namespace
