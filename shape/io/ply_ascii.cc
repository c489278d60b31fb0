// pectus: reading the data of an ASCII PLY file: one item per line, blank lines ignored.
#include <charconv>
#include <cmath>
#include <system_error>

#include "shape/core/error.h"
#include "shape/io/ply_format.h"

namespace pectus::ply {
namespace {

class AsciiReader {
 public:
  enum class Status { kOk, kMissing, kNotANumber, kOutOfRange };

  AsciiReader(std::string_view data, std::int64_t lines_before, const std::string& name)
      : next_(data.data()), end_(data.data() + data.size()), line_(lines_before), name_(name) {}

  /// Moves to the next non-blank line; false at the end of the data.
  bool NextLine() {
    while (next_ < end_) {
      const char* s = next_;
      const auto* newline =
          static_cast<const char*>(std::memchr(s, '\n', static_cast<std::size_t>(end_ - s)));
      line_end_ = newline != nullptr ? newline : end_;
      next_ = newline != nullptr ? newline + 1 : end_;
      ++line_;
      while (s < line_end_ && IsBlank(*s)) ++s;
      if (s < line_end_) {
        p_ = s;
        return true;
      }
    }
    return false;
  }

  /// Reads the next number of the line as a T (from_chars rules, with an optional leading '+').
  template <typename T>
  Status Read(T* value) {
    while (p_ < line_end_ && IsBlank(*p_)) ++p_;
    token_ = p_;
    if (p_ == line_end_) return Status::kMissing;
    const char* s = p_;
    if (*s == '+') {
      ++s;
      if (s == line_end_ || *s == '-') return Status::kNotANumber;
    }
    const auto [end, ec] = std::from_chars(s, line_end_, *value);
    if (ec == std::errc::invalid_argument || (end < line_end_ && !IsBlank(*end))) return Status::kNotANumber;
    if (ec != std::errc()) return Status::kOutOfRange;
    p_ = end;
    return Status::kOk;
  }

  /// A value of property type t, as a double (float properties are read as float: exact round trip).
  Status ReadValue(Type t, double* value) {
    if (t == Type::kFloat32) {
      float f = 0;
      const Status status = Read(&f);
      *value = f;
      return status;
    }
    return Read(value);
  }

  Status SkipToken() {
    while (p_ < line_end_ && IsBlank(*p_)) ++p_;
    token_ = p_;
    if (p_ == line_end_) return Status::kMissing;
    while (p_ < line_end_ && !IsBlank(*p_)) ++p_;
    return Status::kOk;
  }

  bool AtLineEnd() {
    while (p_ < line_end_ && IsBlank(*p_)) ++p_;
    return p_ == line_end_;
  }

  std::int64_t line() const { return line_; }
  std::size_t bytes_left() const { return static_cast<std::size_t>(end_ - next_); }

  [[noreturn]] void Fail(const std::string& message) const { ThrowBadInput(name_, message, line_); }

  /// Throws for a failed Read of `what` (e.g. "property 'x' of vertex 12").
  [[noreturn]] void FailRead(Status status, const std::string& what) const {
    const char* end = token_;
    while (end < line_end_ && !IsBlank(*end)) ++end;
    const std::string_view token(token_, static_cast<std::size_t>(end - token_));
    switch (status) {
      case Status::kMissing: Fail("the line ends before " + what + " (too few values on the line)");
      case Status::kNotANumber: Fail(what + " is not a number: " + Quote(token));
      default: Fail(what + " is out of range: " + Quote(token));
    }
  }

  /// Throws unless only blank lines remain.
  void ExpectEnd() {
    if (NextLine())
      Fail("more data lines than the header declares (line " + std::to_string(line_) + " is extra)");
  }

 private:
  const char* next_;                ///< start of the next line
  const char* end_;                 ///< end of the data
  const char* p_ = nullptr;         ///< read position inside the current line
  const char* line_end_ = nullptr;  ///< end of the current line (before '\n')
  const char* token_ = nullptr;     ///< start of the last token read
  std::int64_t line_;               ///< 1-based number of the current line in the file
  const std::string& name_;
};

/// Checks the vertices can fit in the bytes left before they are allocated.
void CheckAsciiFits(const AsciiReader& in, const Element& e) {
  // Each value takes at least one character and one separator (the last one a line end).
  const std::size_t min_bytes = std::max<std::size_t>(2 * e.properties.size(), 2) - 1;
  if (static_cast<std::uint64_t>(e.count) <= in.bytes_left() / min_bytes) return;
  const std::string declared = "the header declares " + std::to_string(e.count) + " " + Plural(e) +
                               " but only " + std::to_string(in.bytes_left()) + " bytes of data remain";
  AsciiReader lines = in;
  std::int64_t count = 0;
  while (count < e.count && lines.NextLine()) ++count;
  if (count < e.count) {
    lines.Fail("file ends after " + std::to_string(count) + " of " + std::to_string(e.count) + " " +
               Plural(e) + " (" + declared + ")");
  }
  in.Fail(declared + " (each needs at least " + std::to_string(min_bytes) + ")");
}

void ReadAsciiVertices(AsciiReader* in, const Element& e, const std::vector<Slot>& slots, PointCloud* cloud) {
  const Eigen::Index n = e.count;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!in->NextLine()) {
      in->Fail("file ends after " + std::to_string(i) + " of " + std::to_string(n) + " vertices");
    }
    for (const Slot& s : slots) {
      AsciiReader::Status status;
      if (s.is_list) {
        std::int64_t count = 0;
        status = in->Read(&count);
        if (status == AsciiReader::Status::kOk && count < 0)
          in->Fail("negative list length in " + PropertyOf(*s.property, e, i));
        for (std::int64_t k = 0; k < count && status == AsciiReader::Status::kOk; ++k)
          status = in->SkipToken();
      } else {
        double v = 0;
        status = in->ReadValue(s.type, &v);
        Apply(s, i, v);
      }
      if (status != AsciiReader::Status::kOk) [[unlikely]] {
        in->FailRead(status, PropertyOf(*s.property, e, i));
      }
    }
    if (!in->AtLineEnd()) {
      in->Fail("vertex " + std::to_string(i) + " has more values than the " + std::to_string(slots.size()) +
               " properties the header declares");
    }
    const double* x = cloud->positions.data() + 3 * i;
    if (!std::isfinite(x[0]) || !std::isfinite(x[1]) || !std::isfinite(x[2])) {
      in->Fail("vertex " + std::to_string(i) + " has a non-finite coordinate (NaN or Inf)");
    }
  }
}

void ReadAsciiFaces(AsciiReader* in, const Element& e, int index_property, std::int64_t num_vertices,
                    FaceSink* sink) {
  std::vector<std::int64_t> polygon;
  for (std::int64_t f = 0; f < e.count; ++f) {
    if (!in->NextLine()) {
      in->Fail("file ends after " + std::to_string(f) + " of " + std::to_string(e.count) + " faces");
    }
    for (std::size_t k = 0; k < e.properties.size(); ++k) {
      const Property& p = e.properties[k];
      AsciiReader::Status status = AsciiReader::Status::kOk;
      if (static_cast<int>(k) == index_property) {
        std::int64_t count = 0;
        status = in->Read(&count);
        if (status != AsciiReader::Status::kOk)
          in->FailRead(status, "the vertex count of face " + std::to_string(f));
        if (count < 3) {
          in->Fail("face " + std::to_string(f) + " has " + std::to_string(count) +
                   " vertices (at least 3 needed)");
        }
        polygon.clear();
        for (std::int64_t j = 0; j < count; ++j) {
          std::int64_t v = 0;
          status = in->Read(&v);
          if (status != AsciiReader::Status::kOk) {
            in->FailRead(status, "index " + std::to_string(j) + " of face " + std::to_string(f) +
                                     " (it lists " + std::to_string(count) + ")");
          }
          if (v < 0 || v >= num_vertices) {
            in->Fail("face " + std::to_string(f) + " refers to vertex " + std::to_string(v) +
                     " but there are " + std::to_string(num_vertices) + " vertices");
          }
          polygon.push_back(v);
        }
        sink->AddPolygon(polygon.data(), count);
      } else if (p.is_list) {
        std::int64_t count = 0;
        status = in->Read(&count);
        if (status == AsciiReader::Status::kOk && count < 0)
          in->Fail("negative list length in " + PropertyOf(p, e, f));
        for (std::int64_t j = 0; j < count && status == AsciiReader::Status::kOk; ++j)
          status = in->SkipToken();
      } else {
        status = in->SkipToken();
      }
      if (status != AsciiReader::Status::kOk) in->FailRead(status, PropertyOf(p, e, f));
    }
    if (!in->AtLineEnd()) {
      in->Fail("face " + std::to_string(f) + " has more values than its properties declare");
    }
  }
}

void SkipAsciiElement(AsciiReader* in, const Element& e) {
  if (e.properties.empty()) return;  // an item without properties has nothing on its line
  for (std::int64_t i = 0; i < e.count; ++i) {
    if (!in->NextLine()) {
      in->Fail("file ends after " + std::to_string(i) + " of " + std::to_string(e.count) + " " + Plural(e));
    }
  }
}

}  // namespace

void ReadAsciiData(std::string_view data, const Header& header, const Layout& layout, const std::string& name,
                   TriangleMesh* mesh, Faces3* faces) {
  AsciiReader in(data, header.line_count, name);
  for (const Element& e : header.elements) {
    if (&e == layout.vertex) {
      CheckAsciiFits(in, e);
      const std::vector<Slot> slots = MapVertexProperties(e, name, &mesh->vertices);
      ReadAsciiVertices(&in, e, slots, &mesh->vertices);
    } else if (&e == layout.face) {
      // A face line takes at least 7 bytes ("3 0 1 2"); a short file fails while reading.
      FaceSink sink(std::min<std::int64_t>(e.count, static_cast<std::int64_t>(in.bytes_left() / 8)));
      ReadAsciiFaces(&in, e, layout.index_property, layout.vertex->count, &sink);
      *faces = sink.Finish();
    } else {
      SkipAsciiElement(&in, e);
    }
  }
  in.ExpectEnd();
}

}  // namespace pectus::ply
