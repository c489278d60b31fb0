#include "planner_plugin/trainer/trainer_session.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "planner_plugin/trainer/scripted_paths.h"
#include "planner_plugin/trainer/servo_loop.h"
#include "planner_plugin/trainer/session_score.h"
#include "shape/core/error.h"
#include "tests/planner_plugin/trainer/trainer_test_scene.h"
#include "tests/support/require_shared_data.h"

namespace pectus::trainer {
namespace {

// Whether p lies inside the closed collision surfaces (a ray's crossings; an odd direction meets no edge).
bool Inside(const TrainerScene& scene, const Eigen::Vector3d& p) {
  std::vector<SurfaceHit> hits;
  scene.collision.AllHits(p, p + Eigen::Vector3d(401.3, 377.9, 353.1), &hits);
  return hits.size() % 2 == 1;
}

struct ScoredPath {
  PathKind kind;
  SessionRecord record;
  SessionScore score;
};

// The scripted set: three experts (different wobbles), and each novice mistake.
const std::vector<ScoredPath>& ScriptedSet() {
  static const std::vector<ScoredPath> set = [] {
    const TrainerScene& scene = testing::SceneOf(57);
    std::vector<ScoredPath> out;
    const PathKind kinds[] = {PathKind::kExpert,  PathKind::kExpert,          PathKind::kExpert,
                              PathKind::kTooDeep, PathKind::kOntoPericardium, PathKind::kWrongSpace};
    int n = 0;
    for (PathKind kind : kinds) {
      ScriptedPathOptions o;
      o.kind = kind;
      o.wobble_phase_rad = 0.9 * n++;
      o.wobble_mm = kind == PathKind::kExpert ? 1.0 : 1.5;
      o.speed_mm_s = 80;  // a quick push keeps the sanitizer run short
      SimulatedHand hand(MakeScriptedPath(scene, o));
      SessionRecord r = RunSession(scene, &hand, IntroducerSizes()[1], {}, hand.target().duration_s());
      SessionScore s = ScoreSession(scene, r);
      std::printf("%-22s %s\n", PathKindName(kind), s.BriefReport().c_str());
      out.push_back({kind, std::move(r), s});
    }
    return out;
  }();
  return set;
}

TEST(TrainerSession, ScoresTellExpertPathsFromNovicePathsWithoutOverlap) {
  PECTUS_REQUIRE_SHARED_FILE(testing_support::kPatientTable);
  double worst_expert = 1e9, best_novice = -1e9;
  for (const ScoredPath& p : ScriptedSet()) {
    if (p.kind == PathKind::kExpert) {
      worst_expert = std::min(worst_expert, p.score.score);
      EXPECT_EQ(p.score.pericardial_contacts, 0);
      EXPECT_TRUE(p.score.entry_as_planned && p.score.exit_as_planned);
    } else {
      best_novice = std::max(best_novice, p.score.score);
    }
    if (p.kind == PathKind::kOntoPericardium) {
      EXPECT_GT(p.score.pericardial_contacts, 0);
    }
    if (p.kind == PathKind::kTooDeep) {
      EXPECT_LT(p.score.min_pericardium_distance_mm, 5.0);
    }
    if (p.kind == PathKind::kWrongSpace) {
      EXPECT_FALSE(p.score.entry_as_planned) << p.score.entry.Name();
    }
  }
  std::printf("worst expert %.2f, best novice %.2f\n", worst_expert, best_novice);
  EXPECT_GT(worst_expert, best_novice);
}

TEST(TrainerSession, ProxyNeverEndsBelowASurfaceByMoreThanAHundredthOfAMillimetre) {
  PECTUS_REQUIRE_SHARED_FILE(testing_support::kPatientTable);
  const TrainerScene& scene = testing::SceneOf(57);
  double worst = 0;
  std::size_t checked = 0, rays = 0;
  for (const ScoredPath& p : ScriptedSet()) {
    for (std::size_t k = 0; k < p.record.samples.size(); ++k) {
      const Eigen::Vector3d x = p.record.samples[k].proxy_mm;
      // Within 0.01 mm of a surface: never deeper than that whichever side. Farther: inside is a fall
      // through (its depth the distance to the nearest surface), checked by a ray on every 5th tick in
      // contact (the shaft's: the tip is then free) and every 100th otherwise.
      SurfaceHit near;
      const bool close = scene.collision.Nearest(x, 0.01, &near);
      ++checked;
      if (close || k % (p.record.samples[k].organs_touched == 0 ? 100 : 5) != 0) continue;
      ++rays;
      if (Inside(scene, x)) {
        SurfaceHit nearest;
        worst = std::max(worst, scene.collision.Nearest(x, 50, &nearest) ? nearest.distance_mm : 50.0);
      }
    }
  }
  std::printf("%zu proxies checked (%zu by a ray), deepest below a surface %.3g mm\n", checked, rays, worst);
  EXPECT_LE(worst, 0.01);
}

TEST(TrainerSession, RecordWrittenAndReplayedGivesTheSameSessionBitForBit) {
  PECTUS_REQUIRE_SHARED_FILE(testing_support::kPatientTable);
  const TrainerScene& scene = testing::SceneOf(57);
  const ScoredPath& novice = ScriptedSet()[4];  // onto the pericardium: contacts, friction, forces
  const auto path = std::filesystem::temp_directory_path() / "pectus_trainer_session_test.txt";
  WriteSessionRecord(path, novice.record);
  const SessionRecord read = ReadSessionRecord(path);
  std::filesystem::remove(path);
  ASSERT_EQ(read.samples.size(), novice.record.samples.size());
  const SessionRecord replayed = ReplaySession(scene, read);
  ASSERT_EQ(replayed.samples.size(), novice.record.samples.size());
  std::size_t differ = 0;
  for (std::size_t k = 0; k < replayed.samples.size(); ++k) {
    const SessionSample &a = novice.record.samples[k], &b = replayed.samples[k], &c = read.samples[k];
    const bool same = std::memcmp(a.proxy_mm.data(), b.proxy_mm.data(), sizeof(double) * 3) == 0 &&
                      std::memcmp(a.force_n.data(), b.force_n.data(), sizeof(double) * 3) == 0 &&
                      std::memcmp(a.force_n.data(), c.force_n.data(), sizeof(double) * 3) == 0 &&
                      std::memcmp(a.device_mm.data(), c.device_mm.data(), sizeof(double) * 3) == 0 &&
                      a.organs_touched == b.organs_touched && a.pericardium_force_n == b.pericardium_force_n;
    differ += same ? 0 : 1;
  }
  EXPECT_EQ(differ, 0u);
  EXPECT_EQ(replayed.events.size(), novice.record.events.size());
  const SessionScore again = ScoreSession(scene, replayed);
  EXPECT_EQ(std::memcmp(&again.score, &novice.score.score, sizeof(double)), 0);
  EXPECT_EQ(again.BriefReport(), novice.score.BriefReport());
  // A damaged record names the file and line.
  try {
    ParseSessionRecord("period_s 0.001\nintroducer medium\ntick 1 2 3\n", "s.txt");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("s.txt:3"), std::string::npos) << e.what();
  }
}

TEST(TrainerSession, TrajectoryFilesReadBackBitForBit) {
  Trajectory t;  // a helix with a turning tool, at irregular times
  for (int k = 0; k < 200; ++k) {
    DeviceState s;
    s.time_s = 0.01 * k + 1e-3 * std::sin(k);
    s.position_mm = Eigen::Vector3d(30 * std::cos(0.1 * k), 30 * std::sin(0.1 * k), 0.7 * k) / 3.0;
    s.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.05 * k, Eigen::Vector3d(1, 2, 2).normalized()));
    s.buttons = static_cast<std::uint32_t>(k % 3);
    t.samples.push_back(s);
  }
  const Trajectory back = ParseTrajectory(FormatTrajectory(t), "t.txt");
  ASSERT_EQ(back.samples.size(), t.samples.size());
  for (std::size_t i = 0; i < t.samples.size(); ++i) {
    ASSERT_EQ(std::memcmp(back.samples[i].position_mm.data(), t.samples[i].position_mm.data(), 24), 0);
    ASSERT_EQ(back.samples[i].time_s, t.samples[i].time_s);
  }
  // A sample's own time gives that sample exactly; between two, the interpolation.
  ScriptedDevice device(back);
  EXPECT_EQ(device.Read(back.samples[5].time_s).position_mm, back.samples[5].position_mm);
  const double mid = 0.5 * (back.samples[5].time_s + back.samples[6].time_s);
  EXPECT_TRUE(device.Read(mid).position_mm.isApprox(
      0.5 * (back.samples[5].position_mm + back.samples[6].position_mm), 1e-12));
  EXPECT_THROW(ParseTrajectory("0 1 2 3 1 0 0 0 0\n0 1 2 3 1 0 0 0 0\n", "t.txt"),
               Error);                                                   // times must increase
  EXPECT_THROW(ParseTrajectory("0 1 2 3 2 0 0 0 0\n", "t.txt"), Error);  // not a unit quaternion
}

TEST(ServoLoop, TicksOnItsOwnThreadAtTheRate) {
  ServoLoop loop;
  std::atomic<int> ticks{0};
  loop.Start([&](double) { ticks.fetch_add(1); });
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  loop.Stop();
  const ServoLoopStatistics s = loop.Statistics();
  std::printf("%s\n", s.BriefReport().c_str());
  EXPECT_EQ(s.ticks, ticks.load());
  // 200 ms at 1 kHz, whatever the load (an absolute schedule catches up late ticks): 150 to 250.
  EXPECT_GT(s.ticks, 150);
  EXPECT_LT(s.ticks, 250);
  EXPECT_NEAR(s.period_mean_ms, 1.0, 0.3);
}

TEST(ServoLoop, SpinsOrSleepsAsToldAndFallsBackSilentlyWithoutRealtimePriority) {
  // Sleeping to the deadline (no spin) and asking for SCHED_FIFO: granted or not, the loop ticks at the
  // rate; what it got is reported.
  ServoLoopOptions o;
  o.spin_us = 0;
  o.realtime_priority = 10;
  ServoLoop loop(o);
  // Counted from the loop's first tick, not by a wall-clock window: on a loaded machine the thread may
  // start late (it once started after the 100 ms such a window gave it, at load 20).
  std::atomic<int> ticks{0};
  loop.Start([&](double) { ticks.fetch_add(1); });
  for (int i = 0; i < 10000 && ticks.load() < 100; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  loop.Stop();
  const ServoLoopStatistics s = loop.Statistics();
  std::printf("%s (SCHED_FIFO %s)\n", s.BriefReport().c_str(), s.realtime ? "granted" : "refused");
  EXPECT_EQ(s.ticks, ticks.load());
  EXPECT_GE(s.ticks, 100);
  EXPECT_LT(s.ticks, 1000);  // stopped soon after the 100th
  // A spin longer than the period, or a priority out of SCHED_FIFO's range, is refused up front.
  o.spin_us = 1500;
  EXPECT_THROW(ServoLoop{o}, Error);
  o.spin_us = 200;
  o.realtime_priority = 100;
  EXPECT_THROW(ServoLoop{o}, Error);
}

}  // namespace
}  // namespace pectus::trainer
