// Tests of shape/io/patient_table_io: the real CT table of the dissertation's 62 patients reads back with
// the values and summary statistics its SOURCE.md documents; every malformed table is refused with the file,
// the line and the column.
#include "shape/io/patient_table_io.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <utility>

#include "shape/core/error.h"
#include "tests/support/require_shared_data.h"

namespace pectus {
namespace {

const std::string kHeader = "patient,haller_index,width_mm,sternal_length_mm,depth_mm,depression_mm\n";

// The error a table raises (fails the test if it raises none).
Error ErrorOf(const std::string& text) {
  try {
    ParsePatientTable(text, "t.csv");
  } catch (const Error& e) {
    return e;
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return Error(ErrorKind::kFailure, "none");
}

TEST(PatientTableIo, ReadsTheSixtyTwoPatientsOfTheDissertation) {
  PECTUS_REQUIRE_SHARED_FILE(testing_support::kPatientTable);
  const std::vector<PatientTableRow> rows = ReadPatientTable(testing_support::PatientTablePath());
  ASSERT_EQ(rows.size(), 62u);
  const PatientTableRow& p57 = FindPatient(rows, 57, testing_support::PatientTablePath());
  EXPECT_EQ(p57.width_mm, 231.0);
  EXPECT_EQ(p57.sternal_length_mm, 168.0);
  EXPECT_EQ(p57.depth_mm, 123.0);
  EXPECT_EQ(p57.depression_mm, 21.0);
  EXPECT_EQ(p57.haller_index, 6.5);
  EXPECT_EQ(p57.magnification, 1.0);
  EXPECT_EQ(p57.line, 58);  // the header is line 1
  EXPECT_EQ(&FindPatient(rows, "57", testing_support::PatientTablePath()), &p57);
  EXPECT_EQ(rows.front().patient, 1);
  EXPECT_EQ(rows.front().sternal_length_mm, 180.0);  // the table's value (the text says 175)
  // The dissertation's Table 2, as SOURCE.md gives it: means and extremes.
  double width = 0, length = 0, depth = 0, depression = 0, haller = 0;
  for (const PatientTableRow& r : rows) {
    width += r.width_mm / 62;
    length += r.sternal_length_mm / 62;
    depth += r.depth_mm / 62;
    depression += r.depression_mm / 62;
    haller += r.haller_index / 62;
  }
  EXPECT_NEAR(width, 252.24, 0.01);
  EXPECT_NEAR(length, 152.93, 0.01);
  EXPECT_NEAR(depth, 142.45, 0.01);
  EXPECT_NEAR(depression, 18.18, 0.01);
  EXPECT_NEAR(haller, 4.1, 0.05);
  const auto [lo, hi] = std::minmax_element(rows.begin(), rows.end(), [](const auto& a, const auto& b) {
    return a.depression_mm < b.depression_mm;
  });
  EXPECT_EQ(lo->depression_mm, 0.0);
  EXPECT_EQ(hi->depression_mm, 40.0);
}

TEST(PatientTableIo, ColumnsByNameOptionalColumnsQuotesCommentsAndBom) {
  const auto rows = ParsePatientTable(
      "\xEF\xBB\xBF# exported\r\ndepth_mm,\"patient\",width_mm,note,sternal_length_mm,depression_mm,"
      "torsion_deg,magnification\r\n\r\n140,\"7\",250,x,150,20,-10,1.25\r\n",
      "t.csv");
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].patient, 7);
  EXPECT_EQ(rows[0].depth_mm, 140);
  EXPECT_EQ(rows[0].width_mm, 250);
  EXPECT_EQ(rows[0].torsion_deg, -10);
  EXPECT_EQ(rows[0].magnification, 1.25);
  EXPECT_EQ(rows[0].haller_index, 0.0);  // no such column
  EXPECT_EQ(rows[0].line, 4);
}

TEST(PatientTableIo, QuotedCellsMayHoldCommasQuotesAndLineBreaks) {
  // A note column of a spreadsheet export: a comma, an escaped quote and a line break inside its quotes
  // must not shift the columns after it (a split on every comma read " \"\"deep\"\"" as haller_index).
  const auto rows = ParsePatientTable(
      "patient,note,haller_index,width_mm,sternal_length_mm,depth_mm,depression_mm\n"
      "3,\"left, \"\"deep\"\"\nsee CT\",4.2,250,150,140,20\n"
      "4,,4,250,150,140,21\n",
      "t.csv");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].patient, 3);
  EXPECT_EQ(rows[0].haller_index, 4.2);
  EXPECT_EQ(rows[0].depression_mm, 20);
  EXPECT_EQ(rows[1].patient, 4);
  EXPECT_EQ(rows[1].depression_mm, 21);
  EXPECT_EQ(rows[1].line, 4);  // the quoted note spans lines 2 and 3
  const Error e = ErrorOf(kHeader + "3,4.2,250,\"150,140,20\n");
  EXPECT_EQ(e.line(), 2);
  EXPECT_NE(std::string(e.what()).find("unterminated quoted field"), std::string::npos) << e.what();
}

TEST(PatientTableIo, EveryMistakeNamesTheFileTheLineAndTheColumn) {
  const Error number = ErrorOf(kHeader + "1,4.3,232,180,126,14\n2,4.3,2x3,145,153,25\n");
  EXPECT_EQ(number.kind(), ErrorKind::kBadInput);
  EXPECT_EQ(number.file(), "t.csv");
  EXPECT_EQ(number.line(), 3);
  EXPECT_STREQ(number.what(), "t.csv:3: column 'width_mm': '2x3' is not a number");

  const std::pair<std::string, std::string> rows[] = {
      {"1,4.3,232,180,126", "t.csv:2: column 'depression_mm': no value"},
      {"1,4.3,632,180,126,14", "t.csv:2: column 'width_mm': 632 is out of range: must be 100 to 500"},
      {"1,4.3,232,180,126,-1", "t.csv:2: column 'depression_mm': -1 is out of range: must be 0 to 60"},
      {"1,4.3,150,180,160,14", "t.csv:2: column 'depth_mm': 160 exceeds the width 150"},
      {"1,4.3,232,180,70,40", "t.csv:2: column 'depression_mm': 40 exceeds half the depth 70"},
      {"1.5,4.3,232,180,126,14",
       "t.csv:2: column 'patient': 1.5 is not a patient number (a whole number from 1)"},
      {"1,4.3,232,180,126,14\n\n1,4,240,170,130,10",
       "t.csv:4: column 'patient': patient 1 is already on line 2"},
  };
  for (const auto& [body, message] : rows)
    EXPECT_STREQ(ErrorOf(kHeader + body + "\n").what(), message.c_str());
  // Image lengths are checked at their true size: 600 / 1.5 = 400 mm is a width.
  EXPECT_EQ(ParsePatientTable("patient,width_mm,sternal_length_mm,depth_mm,depression_mm,magnification\n"
                              "1,600,150,200,20,1.5\n",
                              "t.csv")[0]
                .width_mm,
            600.0);
  EXPECT_STREQ(
      ErrorOf("patient,width_mm,sternal_length_mm,depth_mm,depression_mm,magnification\n"
              "1,600,150,200,20,1.1\n")
          .what(),
      "t.csv:2: column 'width_mm': 600 is out of range: must be 100 to 500 divided by the magnification "
      "1.1 (it is 545.455)");
  EXPECT_STREQ(ErrorOf("patient,width_mm\n1,250\n").what(),
               "t.csv:1: the header has no column 'sternal_length_mm'");
  EXPECT_STREQ(ErrorOf("patient,width_mm,width_mm\n").what(),
               "t.csv:1: the header names column 'width_mm' twice");
  EXPECT_STREQ(ErrorOf(kHeader).what(), "t.csv: the patient table has a header but no patients");
  EXPECT_STREQ(ErrorOf("\n# nothing\n").what(), "t.csv: empty patient table (no header)");
}

TEST(PatientTableIo, FindPatientAndMissingFilesAreClearErrors) {
  const auto rows = ParsePatientTable(kHeader +
                                          "1,4,232,180,126,14\n2,4,232,180,126,14\n3,4,232,180,126,14\n"
                                          "7,4,232,180,126,14\n",
                                      "t.csv");
  EXPECT_EQ(FindPatient(rows, 7, "t.csv").line, 5);
  EXPECT_EQ(FindPatient(rows, " 3", "t.csv").patient, 3);
  try {
    FindPatient(rows, 9, "t.csv");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kUsage);
    EXPECT_STREQ(e.what(), "patient 9 is not in t.csv (patients 1-3, 7)");
  }
  try {
    FindPatient(rows, "p7", "t.csv");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kUsage);
    EXPECT_STREQ(e.what(), "patient 'p7' is not a patient number (t.csv has patients 1-3, 7)");
  }
  const std::filesystem::path missing = std::filesystem::temp_directory_path() / "pectus_no_such_table.csv";
  try {
    ReadPatientTable(missing);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kBadInput);
    EXPECT_EQ(e.file(), missing.string());
  }
}

}  // namespace
}  // namespace pectus
