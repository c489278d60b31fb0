#include "shape/io/csv_reader.h"

#include <utility>

#include "shape/core/error.h"
#include "shape/io/text_scan.h"

namespace pectus {
namespace {

/// Reads one record from the front of `*rest`, advancing it past the record's line break and `*lines`
/// by the lines it spans. `start_line` names the record in errors.
void ReadFields(std::string_view* rest, std::int64_t* lines, const std::string& name, std::int64_t start_line,
                std::vector<std::string>* fields) {
  fields->clear();
  std::string_view s = *rest;
  std::size_t i = 0;
  const auto end_of_record = [&](std::size_t at) {  // at a '\n', or the end of the text
    *rest = at < s.size() ? s.substr(at + 1) : std::string_view();
    ++*lines;
  };
  while (true) {
    while (i < s.size() && text::IsSpace(s[i])) ++i;
    std::string field;
    if (i < s.size() && s[i] == '"') {
      ++i;
      bool closed = false;
      while (i < s.size()) {
        const char c = s[i];
        if (c == '"') {
          if (i + 1 < s.size() && s[i + 1] == '"') {
            field += '"';
            i += 2;
            continue;
          }
          ++i;
          closed = true;
          break;
        }
        if (c == '\n') ++*lines;
        field += c;
        ++i;
      }
      if (!closed) ThrowBadInput(name, "unterminated quoted field", start_line);
      while (i < s.size() && text::IsSpace(s[i])) ++i;  // blanks, and the '\r' of "\r\n"
      if (i < s.size() && s[i] != ',' && s[i] != '\n')
        ThrowBadInput(name, "text after a closing quote", start_line);
    } else {
      const std::size_t start = i;
      while (i < s.size() && s[i] != ',' && s[i] != '\n') ++i;
      field = std::string(text::Trim(s.substr(start, i - start)));  // Trim drops the '\r' of "\r\n"
    }
    fields->push_back(std::move(field));
    if (i >= s.size() || s[i] == '\n') {
      end_of_record(i);
      return;
    }
    ++i;  // the comma
  }
}

}  // namespace

CsvReader::CsvReader(std::string_view text, std::string name, CsvReadOptions options)
    : rest_(text::StripBom(text)), name_(std::move(name)), options_(options) {}

bool CsvReader::Next(CsvRecord* record) {
  while (!rest_.empty()) {
    const std::size_t eol = rest_.find('\n');
    const std::string_view line = rest_.substr(0, eol);
    const std::string_view trimmed = text::Trim(line);
    const std::int64_t number = line_ + 1;
    if (trimmed.empty() && options_.skip_blank_lines) {
      rest_ = eol == std::string_view::npos ? std::string_view() : rest_.substr(eol + 1);
      ++line_;
      continue;
    }
    record->line = number;
    if (options_.comment != '\0' && !trimmed.empty() && trimmed.front() == options_.comment) {
      rest_ = eol == std::string_view::npos ? std::string_view() : rest_.substr(eol + 1);
      ++line_;
      if (!options_.return_comments) continue;
      record->fields.clear();
      record->is_comment = true;
      record->comment = trimmed.substr(1);
      return true;
    }
    record->is_comment = false;
    record->comment = {};
    ReadFields(&rest_, &line_, name_, number, &record->fields);
    return true;
  }
  return false;
}

std::vector<std::string> SplitCsvLine(std::string_view line, const std::string& name,
                                      std::int64_t line_number) {
  std::vector<std::string> fields;
  std::int64_t lines = line_number - 1;
  ReadFields(&line, &lines, name, line_number, &fields);
  if (!line.empty()) ThrowBadInput(name, "a line break inside a CSV line", line_number);
  return fields;
}

}  // namespace pectus
