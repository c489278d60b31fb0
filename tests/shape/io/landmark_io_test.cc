#include "shape/io/landmark_io.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "shape/core/error.h"
#include "shape/io/mapped_file.h"
#include "tests/shape/io/io_test_util.h"

namespace pectus {
namespace {

using testing::ThrowsBadInput;

LandmarkSet NonAsciiSet() {
  LandmarkSet set;
  set.items.push_back(
      {"Brustbein-Einkerbung", Eigen::Vector3d(12.5, -200.125, 1031.0000000000002), "Jugulum"});
  set.items.push_back({"胸骨上切迹", Eigen::Vector3d(-0.1, 0.2, -0.3), "胸骨"});
  set.items.push_back({"sternal notch é", Eigen::Vector3d(1e-3, 123456.789, -7.0), ""});
  set.items.push_back({"xiphoid, tip \"lower\"", Eigen::Vector3d(0, 0, 0), "with, comma"});
  return set;
}

void ExpectSameSet(const LandmarkSet& a, const LandmarkSet& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a.items[i].label, b.items[i].label);
    EXPECT_EQ(a.items[i].position, b.items[i].position) << a.items[i].label;  // exact
    EXPECT_EQ(a.items[i].description, b.items[i].description);
  }
}

TEST(LandmarkIo, NonAsciiLabelsRoundTripExactlyInEveryFormat) {
  const testing::TempDir dir;
  const LandmarkSet set = NonAsciiSet();
  for (const std::string name : {"marks.mrk.json", "marks.fcsv", "marks.csv"}) {
    SCOPED_TRACE(name);
    WriteLandmarks(dir / name, set);
    ExpectSameSet(ReadLandmarks(dir / name), set);
  }
  // Written atomically: no temporary files are left beside the outputs.
  int files = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir.path())) ++files;
  EXPECT_EQ(files, 3);
}

TEST(LandmarkIo, WrittenMarkupsFollowSlicerSchemaInLps) {
  const testing::TempDir dir;
  WriteLandmarks(dir / "m.mrk.json", NonAsciiSet());
  const MappedFile file((dir / "m.mrk.json").string());
  const nlohmann::json j = nlohmann::json::parse(file.bytes().begin(), file.bytes().end());
  EXPECT_NE(j["@schema"].get<std::string>().find("markups-schema-v1.0.3.json#"), std::string::npos);
  const nlohmann::json& markup = j["markups"][0];
  EXPECT_EQ(markup["type"], "Fiducial");
  EXPECT_EQ(markup["coordinateSystem"], "LPS");
  EXPECT_EQ(markup["coordinateUnits"], "mm");
  const nlohmann::json& point = markup["controlPoints"][1];
  EXPECT_EQ(point["label"], "胸骨上切迹");
  EXPECT_EQ(point["position"][2], -0.3);
  EXPECT_EQ(point["positionStatus"], "defined");
  EXPECT_EQ(point["orientation"].size(), 9u);
  // Non-ASCII text is stored as UTF-8, not \u escapes, as Slicer writes it.
  EXPECT_NE(std::string(file.bytes()).find("胸骨上切迹"), std::string::npos);
}

TEST(LandmarkIo, MarkupsInRasAndMetresAreConvertedToLpsMillimetres) {
  const std::string json = R"({
    "@schema": "https://raw.githubusercontent.com/slicer/slicer/master/Modules/Loadable/Markups/Resources/Schema/markups-schema-v1.0.3.json#",
    "markups": [
      {"type": "Line", "coordinateSystem": "LPS",
       "controlPoints": [{"id": "1", "label": "L-1", "position": [1, 2, 3]}]},
      {"type": "Fiducial", "coordinateSystem": "RAS", "coordinateUnits": "mm",
       "controlPoints": [
         {"id": "1", "label": "sternal_notch", "description": "", "position": [10.5, -20.25, 30.0],
          "orientation": [-1, 0, 0, 0, -1, 0, 0, 0, 1], "selected": true, "locked": false,
          "visibility": true, "positionStatus": "defined"},
         {"id": "2", "label": "not_placed", "position": [0, 0, 0], "positionStatus": "undefined"},
         {"id": "3", "label": "xiphoid", "position": [-1, 2, -3]}]},
      {"type": "Fiducial", "coordinateSystem": "LPS", "coordinateUnits": "m",
       "controlPoints": [{"id": "1", "label": "nipple_left", "position": [0.1, 0.2, -0.0305]}]}
    ]})";
  const LandmarkSet set = ParseLandmarks(json, "ras.mrk.json");
  ASSERT_EQ(set.size(), 3u);
  EXPECT_EQ(set.items[0].label, "sternal_notch");
  EXPECT_EQ(set.items[0].position, Eigen::Vector3d(-10.5, 20.25, 30.0));  // RAS -> LPS: x, y negated
  EXPECT_EQ(set.items[1].label, "xiphoid");
  EXPECT_EQ(set.items[1].position, Eigen::Vector3d(1, -2, -3));
  EXPECT_EQ(set.items[2].label, "nipple_left");
  EXPECT_LT((set.items[2].position - Eigen::Vector3d(100, 200, -30.5)).norm(), 1e-12);  // metres -> mm
}

TEST(LandmarkIo, FcsvCoordinateSystemHeader) {
  const std::string columns = "# columns = id,x,y,z,ow,ox,oy,oz,vis,sel,lock,label,desc,associatedNodeID\n";
  const std::string row =
      "vtkMRMLMarkupsFiducialNode_0,1.5,-2,3,0,0,0,1,1,1,0,sternal_notch,\"top, of sternum\",\n";
  const Eigen::Vector3d lps(1.5, -2, 3), from_ras(-1.5, 2, 3);
  const auto read = [&](const std::string& system_line) {
    return ParseLandmarks("# Markups fiducial file version = 4.11\n" + system_line + columns + row, "f.fcsv");
  };
  EXPECT_EQ(read("# CoordinateSystem = LPS\n").items[0].position, lps);
  EXPECT_EQ(read("# CoordinateSystem = 1\n").items[0].position, lps);
  EXPECT_EQ(read("# CoordinateSystem = RAS\n").items[0].position, from_ras);
  EXPECT_EQ(read("# CoordinateSystem = 0\n").items[0].position, from_ras);
  EXPECT_EQ(read("").items[0].position, from_ras);  // older files: RAS
  const LandmarkSet set = read("# CoordinateSystem = LPS\n");
  EXPECT_EQ(set.items[0].label, "sternal_notch");
  EXPECT_EQ(set.items[0].description, "top, of sternum");
}

TEST(LandmarkIo, CsvWithAndWithoutHeaderAndUnits) {
  const LandmarkSet plain = ParseLandmarks("sternal_notch,1,2,3\n\"xiphoid, tip\",4,5,6\n", "p.csv");
  ASSERT_EQ(plain.size(), 2u);
  EXPECT_EQ(plain.items[1].label, "xiphoid, tip");
  EXPECT_EQ(plain.items[1].position, Eigen::Vector3d(4, 5, 6));  // CSV is taken as it stands
  const LandmarkSet header = ParseLandmarks("x,y,z,label\r\n1,2,3,a\r\n", "h.csv",
                                            LandmarkReadOptions{.input_units = LengthUnit::kCentimetre});
  ASSERT_EQ(header.size(), 1u);
  EXPECT_EQ(header.items[0].label, "a");
  EXPECT_EQ(header.items[0].position, Eigen::Vector3d(10, 20, 30));
}

TEST(LandmarkIo, MalformedInputIsAnErrorNamingFileAndLine) {
  for (const std::string name : {"e.mrk.json", "e.fcsv", "e.csv"}) {
    EXPECT_TRUE(ThrowsBadInput([&] { ParseLandmarks(" \n", name); }, "file is empty", name));
  }
  EXPECT_TRUE(ThrowsBadInput([] { ParseLandmarks("a,1,2,3\n,4,5,6\n", "nolabel.csv"); }, "missing label",
                             "nolabel.csv", 2));
  EXPECT_TRUE(ThrowsBadInput([] { ParseLandmarks("a,1,2,3\nb,1,2,3\n\na,4,5,6\n", "dup.csv"); },
                             "duplicate landmark label 'a' (lines 1 and 4)", "dup.csv", 4));
  EXPECT_TRUE(ThrowsBadInput([] { ParseLandmarks("胸骨,1,2,3\n胸骨,4,5,6\n", "dup8.csv"); },
                             "duplicate landmark label '胸骨'", "dup8.csv", 2));
  EXPECT_TRUE(
      ThrowsBadInput([] { ParseLandmarks("a,1,2\n", "coord.csv"); }, "missing coordinate", "coord.csv", 1));
  EXPECT_TRUE(ThrowsBadInput([] { ParseLandmarks("a,1,two,3\n", "word.csv"); }, "'two' is not a number (y",
                             "word.csv", 1));
  EXPECT_TRUE(ThrowsBadInput([] { ParseLandmarks("a,1,nan,3\n", "nan.csv"); }, "non-finite", "nan.csv", 1));
  EXPECT_TRUE(ThrowsBadInput([] { ParseLandmarks("ok,1,2,3\n\xC3\x28,1,2,3\n", "utf.csv"); },
                             "not valid UTF-8", "utf.csv", 2));
  EXPECT_TRUE(
      ThrowsBadInput([] { ParseLandmarks("\"a,1,2,3\n", "quote.csv"); }, "unterminated", "quote.csv", 1));
  EXPECT_TRUE(ThrowsBadInput([] { ParseLandmarks("# CoordinateSystem = IJK\n", "cs.fcsv"); },
                             "unknown CoordinateSystem", "cs.fcsv", 1));
  EXPECT_TRUE(ThrowsBadInput([] { ParseLandmarks("# columns = id,x,y,z\n1,2,3,4\n", "cols.fcsv"); },
                             "lacks one of label", "cols.fcsv", 1));
  EXPECT_TRUE(
      ThrowsBadInput([] { ParseLandmarks("# only comments\n", "none.fcsv"); }, "no landmarks", "none.fcsv"));

  // JSON: parse errors carry nlohmann's position; items are named by control point.
  EXPECT_TRUE(ThrowsBadInput([] { ParseLandmarks("{\"markups\": [\n  {\"type\": }\n]}", "bad.mrk.json"); },
                             "malformed JSON: parse error at line 2, column", "bad.mrk.json"));
  EXPECT_TRUE(ThrowsBadInput([] { ParseLandmarks("{\"a\": 1}", "x.mrk.json"); }, "no \"markups\" list",
                             "x.mrk.json"));
  const auto markups = [](const std::string& points) {
    return "{\"markups\": [{\"type\": \"Fiducial\", \"controlPoints\": [" + points + "]}]}";
  };
  EXPECT_TRUE(ThrowsBadInput([&] { ParseLandmarks(markups(R"({"position": [1, 2, 3]})"), "nl.mrk.json"); },
                             "control point 1: missing label", "nl.mrk.json"));
  EXPECT_TRUE(ThrowsBadInput(
      [&] {
        ParseLandmarks(
            markups(R"({"label": "a", "position": [1, 2, 3]}, {"label": "a", "position": [1, 2, 3]})"),
            "d.mrk.json");
      },
      "duplicate landmark label 'a' (control points 1 and 2)", "d.mrk.json"));
  EXPECT_TRUE(
      ThrowsBadInput([&] { ParseLandmarks(markups(R"({"label": "a", "position": [1, 2]})"), "c.mrk.json"); },
                     "missing coordinate", "c.mrk.json"));
  EXPECT_TRUE(ThrowsBadInput(
      [&] { ParseLandmarks(markups(R"({"label": "a", "position": [1, "2", 3]})"), "s.mrk.json"); },
      "is not a number", "s.mrk.json"));
  EXPECT_TRUE(ThrowsBadInput(
      [&] { ParseLandmarks(markups(R"({"label": "a", "position": [1, 1e999, 3]})"), "i.mrk.json"); },
      "malformed JSON: number overflow", "i.mrk.json"));
  EXPECT_TRUE(ThrowsBadInput([&] { ParseLandmarks(markups("{\"label\": \"\xC3\x28\"}"), "u.mrk.json"); },
                             "malformed JSON", "u.mrk.json"));
}

TEST(LandmarkIo, UnknownFileTypeIsAUsageError) {
  try {
    ParseLandmarks("a,1,2,3\n", "marks.txt");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kUsage);
    EXPECT_NE(std::string(e.what()).find("marks.txt"), std::string::npos);
  }
}

TEST(LandmarkIo, WritingAnInvalidSetIsRefused) {
  const testing::TempDir dir;
  LandmarkSet set = NonAsciiSet();
  set.items.push_back(set.items[0]);
  EXPECT_TRUE(ThrowsBadInput([&] { WriteLandmarks(dir / "dup.csv", set); }, "duplicate", "dup.csv"));
  EXPECT_FALSE(std::filesystem::exists(dir / "dup.csv"));
}

}  // namespace
}  // namespace pectus
