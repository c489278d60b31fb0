#include "shape/core/report.h"

#include <gtest/gtest.h>

#include <fstream>
#include <thread>

#include "shape/core/error.h"
#include "shape/core/landmarks.h"
#include "shape/core/log.h"

namespace pectus {
namespace {

TEST(Report, StagesAccumulateAndWriteValidJson) {
  SetQuiet(true);
  Warn("a warning before the report, not in it");
  SetQuiet(false);
  Report r;
  {
    auto t = r.Stage("read");
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  r.AddTime("read", 1.0);
  r["points"] = 42;
  SetQuiet(true);
  Warn("a warning for the report");
  SetQuiet(false);
  const auto path = std::filesystem::temp_directory_path() / "pectus_report_test.json";
  r.Write(path);
  std::ifstream in(path);
  const auto j = nlohmann::json::parse(in);
  std::filesystem::remove(path);
  EXPECT_EQ(j["points"], 42);
  EXPECT_GE(j["timings_s"]["read"].get<double>(), 1.019);
  EXPECT_LT(j["timings_s"]["read"].get<double>(), 2.0);
  EXPECT_GE(j["timings_s"]["total"].get<double>(), 0.019);
  ASSERT_EQ(j["warnings"].size(), 1u);
  EXPECT_EQ(j["warnings"][0], "a warning for the report");
}

TEST(Report, AddsAResultsTimingsStageByStage) {
  Report r;
  Timings t;
  t.Add("merge", 2.0);
  t.Add("reconstruct", 0.5);
  r.AddTime("merge", 1.0);
  r.AddTimes(t);
  EXPECT_DOUBLE_EQ(r["timings_s"]["merge"].get<double>(), 3.0);
  EXPECT_DOUBLE_EQ(r["timings_s"]["reconstruct"].get<double>(), 0.5);
}

TEST(Error, WhatNamesFileAndLine) {
  const Error e(ErrorKind::kBadInput, "bad number 'x1'", "scan.ply", 17);
  EXPECT_STREQ(e.what(), "scan.ply:17: bad number 'x1'");
  EXPECT_EQ(static_cast<int>(e.kind()), 3);
  EXPECT_STREQ(Error(ErrorKind::kFailure, "m", "f").what(), "f: m");
}

TEST(LandmarkSet, ValidateRejectsDuplicatesAndEmptyLabels) {
  LandmarkSet s;
  s.items.push_back({"sternal_notch", {0, 0, 0}, ""});
  s.items.push_back({"xiphoid", {0, -150, 0}, ""});
  EXPECT_NO_THROW(s.Validate("a.mrk.json"));
  EXPECT_EQ(s.Position("xiphoid", "a"), Eigen::Vector3d(0, -150, 0));
  EXPECT_THROW(s.Position("manubrium", "a"), Error);
  s.items.push_back({"xiphoid", {1, 1, 1}, ""});
  EXPECT_THROW(s.Validate("a.mrk.json"), Error);
  s.items.back().label = "";
  EXPECT_THROW(s.Validate("a.mrk.json"), Error);
}

}  // namespace
}  // namespace pectus
