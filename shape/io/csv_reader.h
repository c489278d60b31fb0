// pectus: the one CSV tokenizer of shape/io (RFC 4180), used by the landmark (.csv, .fcsv) and patient
// table readers. On pectus::core only (its own target, pectus::csv), so the planner plugin's patient
// table reader links it without the rest of shape/io.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace pectus {

/// How a CsvReader treats the lines between records.
struct CsvReadOptions {
  char comment = '#';            ///< a line whose first non-blank character is this is a comment ('\0': none)
  bool return_comments = false;  ///< hand comment lines to the caller (CsvRecord::is_comment) or skip them
  bool skip_blank_lines = true;  ///< a line of blanks only holds no record (else: one empty field)
};

/// One record of a CSV text: its fields, or a comment line.
struct CsvRecord {
  std::vector<std::string> fields;  ///< the fields, unquoted; empty for a comment
  bool is_comment = false;          ///< a comment line (only when CsvReadOptions::return_comments)
  std::string_view comment;         ///< a comment's text after the comment character, untrimmed
  std::int64_t line = 0;            ///< 1-based line where the record starts
};

/// Reads CSV text record by record, as RFC 4180 writes it: fields separated by commas, records by "\n"
/// or "\r\n". A field in double quotes may hold commas and line breaks, and "" in it stands for one
/// quote. Blanks around a field are trimmed (inside quotes they are kept). Every error is
/// Error(kBadInput) naming the file and the line where the record starts.
class CsvReader {
 public:
  /// Reads `text` (a leading UTF-8 byte order mark is skipped); `name` is the file named in errors.
  CsvReader(std::string_view text, std::string name, CsvReadOptions options = {});

  /// The next record into `*record`; false when the text is exhausted. Throws Error(kBadInput) for an
  /// unterminated quoted field or text after a closing quote.
  bool Next(CsvRecord* record);

 private:
  std::string_view rest_;
  std::string name_;
  CsvReadOptions options_;
  std::int64_t line_ = 0;  ///< lines consumed so far
};

/// The fields of one CSV line, as CsvReader reads a record (`line` must not hold a line break outside
/// quotes). Throws Error(kBadInput) naming `name` and `line_number` for a malformed line.
std::vector<std::string> SplitCsvLine(std::string_view line, const std::string& name,
                                      std::int64_t line_number);

}  // namespace pectus
