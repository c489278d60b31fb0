// The CSV tokenizer: RFC 4180 quoting, line ends, comments, and line numbers in its errors.
#include "shape/io/csv_reader.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "shape/core/error.h"
#include "tests/shape/io/io_test_util.h"

namespace pectus {
namespace {

using ::testing::ElementsAre;
using testing::ThrowsBadInput;

/// Every record of `text`: fields, or "#<comment>" for a comment line, each with its line number.
std::vector<std::pair<std::int64_t, std::vector<std::string>>> ReadAll(const std::string& text,
                                                                       CsvReadOptions options = {}) {
  CsvReader reader(text, "t.csv", options);
  CsvRecord record;
  std::vector<std::pair<std::int64_t, std::vector<std::string>>> out;
  while (reader.Next(&record)) {
    out.emplace_back(record.line, record.is_comment
                                      ? std::vector<std::string>{"#" + std::string(record.comment)}
                                      : record.fields);
  }
  return out;
}

TEST(CsvReader, SplitsPlainFieldsAndTrimsBlanks) {
  const auto records = ReadAll("a, b ,c\n 1,2 , 3\n");
  ASSERT_EQ(records.size(), 2u);
  EXPECT_EQ(records[0].first, 1);
  EXPECT_THAT(records[0].second, ElementsAre("a", "b", "c"));
  EXPECT_EQ(records[1].first, 2);
  EXPECT_THAT(records[1].second, ElementsAre("1", "2", "3"));
}

TEST(CsvReader, KeepsEmptyFields) {
  const auto records = ReadAll(",a,,\n");
  ASSERT_EQ(records.size(), 1u);
  EXPECT_THAT(records[0].second, ElementsAre("", "a", "", ""));
}

TEST(CsvReader, QuotedFieldsHoldCommasQuotesBlanksAndLineBreaks) {
  // RFC 4180 section 2, rules 5-7: quotes enclose commas and line breaks, "" is one quote.
  const auto records = ReadAll("\"a,b\", \"say \"\"hi\"\"\" ,\" kept \"\n\"two\nlines\",x\nlast,1\n");
  ASSERT_EQ(records.size(), 3u);
  EXPECT_THAT(records[0].second, ElementsAre("a,b", "say \"hi\"", " kept "));
  EXPECT_EQ(records[1].first, 2);
  EXPECT_THAT(records[1].second, ElementsAre("two\nlines", "x"));
  EXPECT_EQ(records[2].first, 4);  // the record after a two-line one starts on line 4
  EXPECT_THAT(records[2].second, ElementsAre("last", "1"));
}

TEST(CsvReader, CrLfLineEndsAreRemovedAndCounted) {
  const auto records = ReadAll("a,\"b\"\r\n\r\nc,d\r\n\"e\r\nf\",\r\n");
  ASSERT_EQ(records.size(), 3u);
  EXPECT_THAT(records[0].second, ElementsAre("a", "b"));
  EXPECT_EQ(records[1].first, 3);
  EXPECT_THAT(records[1].second, ElementsAre("c", "d"));
  EXPECT_EQ(records[2].first, 4);
  EXPECT_THAT(records[2].second, ElementsAre("e\r\nf", ""));  // inside quotes the line break is data
}

TEST(CsvReader, LastLineWithoutLineBreakAndByteOrderMark) {
  const auto records = ReadAll("\xEF\xBB\xBFx,y\n1,2");
  ASSERT_EQ(records.size(), 2u);
  EXPECT_THAT(records[0].second, ElementsAre("x", "y"));
  EXPECT_THAT(records[1].second, ElementsAre("1", "2"));
}

TEST(CsvReader, CommentAndBlankLinesAreSkippedOrReturned) {
  const std::string text = "# header = 1\n\n  # indented\na,b\n \t\n";
  const auto skipped = ReadAll(text);
  ASSERT_EQ(skipped.size(), 1u);
  EXPECT_EQ(skipped[0].first, 4);
  EXPECT_THAT(skipped[0].second, ElementsAre("a", "b"));

  const auto returned = ReadAll(text, CsvReadOptions{.return_comments = true});
  ASSERT_EQ(returned.size(), 3u);
  EXPECT_EQ(returned[0].first, 1);
  EXPECT_THAT(returned[0].second, ElementsAre("# header = 1"));
  EXPECT_EQ(returned[1].first, 3);
  EXPECT_THAT(returned[1].second, ElementsAre("# indented"));

  const auto no_comments = ReadAll("#a,b\n", CsvReadOptions{.comment = '\0'});
  ASSERT_EQ(no_comments.size(), 1u);
  EXPECT_THAT(no_comments[0].second, ElementsAre("#a", "b"));

  const auto blanks = ReadAll("a\n\nb\n", CsvReadOptions{.skip_blank_lines = false});
  ASSERT_EQ(blanks.size(), 3u);
  EXPECT_THAT(blanks[1].second, ElementsAre(""));
}

TEST(CsvReader, MalformedQuotesNameTheFileAndTheRecordsLine) {
  EXPECT_TRUE(
      ThrowsBadInput([] { ReadAll("ok,1\n\"open,2\nmore\n"); }, "unterminated quoted field", "t.csv", 2));
  EXPECT_TRUE(ThrowsBadInput([] { ReadAll("ok\n\n\"a\"b,1\n"); }, "text after a closing quote", "t.csv", 3));
}

TEST(SplitCsvLine, OneLineAsTheReaderReadsIt) {
  EXPECT_THAT(SplitCsvLine(" id , \"x,y\" ,z", "c.fcsv", 3), ElementsAre("id", "x,y", "z"));
  EXPECT_TRUE(ThrowsBadInput([] { SplitCsvLine("\"a", "c.fcsv", 7); }, "unterminated", "c.fcsv", 7));
  EXPECT_TRUE(ThrowsBadInput([] { SplitCsvLine("a\nb", "c.fcsv", 7); }, "line break", "c.fcsv", 7));
}

}  // namespace
}  // namespace pectus
