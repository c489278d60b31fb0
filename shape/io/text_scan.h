// pectus: small helpers shared by the text-format parsers and writers of shape/io (internal header).
// Parsing reads from memory with std::from_chars, writing formats with std::to_chars: no iostreams, no
// locale (a German locale must not turn "1.5" into "1,5").
#pragma once

#include <charconv>
#include <cstdint>
#include <string>
#include <string_view>
#include <system_error>

namespace pectus::text {

/// Splits a text buffer into lines ("\n" or "\r\n"), counting 1-based line numbers.
class LineReader {
 public:
  explicit LineReader(std::string_view text) : rest_(text) {}

  /// The next line without its end-of-line characters; false when the text is exhausted.
  bool Next(std::string_view* line) {
    if (rest_.empty()) return false;
    const std::size_t end = rest_.find('\n');
    std::string_view l = rest_.substr(0, end);
    rest_ = end == std::string_view::npos ? std::string_view() : rest_.substr(end + 1);
    if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
    *line = l;
    ++number_;
    return true;
  }
  /// 1-based number of the line last returned by Next().
  std::int64_t number() const { return number_; }

 private:
  std::string_view rest_;
  std::int64_t number_ = 0;
};

inline bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/// `s` without leading and trailing blanks.
inline std::string_view Trim(std::string_view s) {
  while (!s.empty() && IsSpace(s.front())) s.remove_prefix(1);
  while (!s.empty() && IsSpace(s.back())) s.remove_suffix(1);
  return s;
}

/// `s` without a leading UTF-8 byte order mark (spreadsheet programs write one).
inline std::string_view StripBom(std::string_view s) {
  if (s.size() >= 3 && s.substr(0, 3) == "\xEF\xBB\xBF") s.remove_prefix(3);
  return s;
}

/// The next blank-separated token of `*s`, which is advanced past it; empty when none is left.
inline std::string_view NextToken(std::string_view* s) {
  std::size_t i = 0;
  while (i < s->size() && IsSpace((*s)[i])) ++i;
  std::size_t j = i;
  while (j < s->size() && !IsSpace((*s)[j])) ++j;
  const std::string_view token = s->substr(i, j - i);
  s->remove_prefix(j);
  return token;
}

/// Parses all of `token` as a decimal number ("1.5", "-2e3", "+4"; also "nan" and "inf", which the
/// callers reject with their own message). False if `token` is not entirely a number.
inline bool ParseDouble(std::string_view token, double* value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, *value);
  return ec == std::errc() && ptr == end;
}

/// Parses all of `token` as a decimal integer (a leading '+' or '-' allowed).
inline bool ParseInt(std::string_view token, std::int64_t* value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, *value);
  return ec == std::errc() && ptr == end;
}

/// Appends the shortest decimal text that reads back as exactly `value`.
inline void AppendNumber(double value, std::string* out) {
  char buffer[32];
  const auto [ptr, ec] = std::to_chars(buffer, buffer + sizeof buffer, value);
  out->append(buffer, ec == std::errc() ? ptr : buffer);
}

/// Appends an integer in decimal.
inline void AppendInt(std::int64_t value, std::string* out) {
  char buffer[24];
  const auto [ptr, ec] = std::to_chars(buffer, buffer + sizeof buffer, value);
  out->append(buffer, ec == std::errc() ? ptr : buffer);
}

inline char ToLowerAscii(char c) { return c >= 'A' && c <= 'Z' ? static_cast<char>(c - 'A' + 'a') : c; }

/// `s` with ASCII letters lowered (other bytes, including UTF-8 sequences, unchanged).
inline std::string ToLowerAscii(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = ToLowerAscii(c);
  return out;
}

/// True if `s` starts with `prefix`, ignoring ASCII case.
inline bool StartsWithNoCase(std::string_view s, std::string_view prefix) {
  if (s.size() < prefix.size()) return false;
  for (std::size_t i = 0; i < prefix.size(); ++i) {
    if (ToLowerAscii(s[i]) != ToLowerAscii(prefix[i])) return false;
  }
  return true;
}

/// True if `a` equals `b`, ignoring ASCII case.
inline bool EqualsNoCase(std::string_view a, std::string_view b) {
  return a.size() == b.size() && StartsWithNoCase(a, b);
}

/// True if `s` ends with `suffix`, ignoring ASCII case.
inline bool EndsWithNoCase(std::string_view s, std::string_view suffix) {
  return s.size() >= suffix.size() && EqualsNoCase(s.substr(s.size() - suffix.size()), suffix);
}

/// `s` in single quotes for an error message, cut to 40 bytes (a binary file's "token" can be long).
inline std::string Quoted(std::string_view s) {
  std::string out = "'";
  out.append(s.substr(0, 40));
  out += '\'';
  return out;
}

/// True if `s` is well-formed UTF-8 (no overlong forms, no surrogates, nothing above U+10FFFF).
inline bool IsValidUtf8(std::string_view s) {
  std::size_t i = 0;
  while (i < s.size()) {
    const auto c = static_cast<unsigned char>(s[i]);
    int extra = 0;
    std::uint32_t code = 0;
    if (c < 0x80) {
      ++i;
      continue;
    } else if (c >= 0xC2 && c <= 0xDF) {
      extra = 1;
      code = c & 0x1Fu;
    } else if (c >= 0xE0 && c <= 0xEF) {
      extra = 2;
      code = c & 0x0Fu;
    } else if (c >= 0xF0 && c <= 0xF4) {
      extra = 3;
      code = c & 0x07u;
    } else {
      return false;
    }
    if (i + static_cast<std::size_t>(extra) >= s.size()) return false;
    for (int k = 1; k <= extra; ++k) {
      const auto d = static_cast<unsigned char>(s[i + static_cast<std::size_t>(k)]);
      if ((d & 0xC0u) != 0x80u) return false;
      code = (code << 6) | (d & 0x3Fu);
    }
    if ((extra == 2 && code < 0x800) || (extra == 3 && (code < 0x10000 || code > 0x10FFFF)) ||
        (code >= 0xD800 && code <= 0xDFFF)) {
      return false;
    }
    i += static_cast<std::size_t>(extra) + 1;
  }
  return true;
}

}  // namespace pectus::text
