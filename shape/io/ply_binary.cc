// pectus: reading the data of a binary PLY file (little or big endian).
#include <cmath>
#include <limits>

#include "shape/core/error.h"
#include "shape/io/ply_format.h"

namespace pectus::ply {
namespace {

class BinaryReader {
 public:
  BinaryReader(std::string_view data, bool swap, const std::string& name)
      : p_(data.data()), end_(data.data() + data.size()), swap_(swap), name_(name) {}

  std::size_t left() const { return static_cast<std::size_t>(end_ - p_); }
  const char* position() const { return p_; }
  void Advance(std::size_t bytes) { p_ += bytes; }
  void set_position(const char* p) { p_ = p; }
  const char* end() const { return end_; }
  bool swap() const { return swap_; }
  const std::string& name() const { return name_; }

  [[noreturn]] void FailEnds(const Element& e, std::int64_t done) const {
    ThrowBadInput(name_, "file ends after " + std::to_string(done) + " of " + std::to_string(e.count) + " " +
                             Plural(e) + " (the data is truncated or the header is wrong)");
  }

  /// Reads one list length at the current position (after checking it is there), advancing past it.
  /// Returns -1 if the data ends.
  std::int64_t ReadCount(Type t, const Element& e, const Property& p, std::int64_t item) {
    const std::size_t size = SizeOf(t);
    if (left() < size) return -1;
    const double count = LoadAsDouble(p_, t, swap_);
    if (count < 0) {
      ThrowBadInput(name_, "negative list length " + std::to_string(static_cast<std::int64_t>(count)) +
                               " in " + PropertyOf(p, e, item));
    }
    p_ += size;
    return static_cast<std::int64_t>(count);
  }

  /// Skips a list of `count` items of type t; false if the data ends first.
  bool SkipItems(std::int64_t count, Type t) {
    if (static_cast<std::uint64_t>(count) > left() / SizeOf(t)) return false;
    p_ += static_cast<std::size_t>(count) * SizeOf(t);
    return true;
  }

 private:
  const char* p_;
  const char* end_;
  bool swap_;
  const std::string& name_;
};

/// Consecutive wanted properties copied together: `width` (1 or 3) values of one type at consecutive
/// offsets going to consecutive columns of one destination row (x y z, nx ny nz, red green blue).
struct Run {
  const Slot* slot;
  int width;
};

std::vector<Run> GroupRuns(const std::vector<Slot>& slots) {
  std::vector<Run> runs;
  for (std::size_t i = 0; i < slots.size(); ++i) {
    const Slot& a = slots[i];
    if (a.kind == Slot::Kind::kIgnore) continue;
    if (i + 2 < slots.size() && a.stride == 3) {
      const Slot& b = slots[i + 1];
      const Slot& c = slots[i + 2];
      const std::size_t size = SizeOf(a.type);
      const bool same = b.kind == a.kind && c.kind == a.kind && b.type == a.type && c.type == a.type &&
                        b.offset == a.offset + size && c.offset == a.offset + 2 * size;
      const bool adjacent = a.kind == Slot::Kind::kValue
                                ? (b.values == a.values + 1 && c.values == a.values + 2)
                                : (b.colors == a.colors + 1 && c.colors == a.colors + 2);
      if (same && adjacent) {
        runs.push_back({&a, 3});
        i += 2;
        continue;
      }
    }
    runs.push_back({&a, 1});
  }
  return runs;
}

template <typename Out, typename T>
inline Out Convert(T v) {
  if constexpr (std::is_same_v<Out, double>) {
    return static_cast<double>(v);
  } else {
    return ColorFromValue(static_cast<double>(v), std::is_integral_v<T>);
  }
}

/// Copies `n` records' run of kWidth values of type T into dst (stride dst_stride per record).
template <typename T, bool kSwap, int kWidth, typename Out>
void CopyRun(const char* src, std::size_t stride, std::size_t n, Out* dst, std::ptrdiff_t dst_stride) {
  for (std::size_t i = 0; i < n; ++i, src += stride, dst += dst_stride) {
    for (int k = 0; k < kWidth; ++k) dst[k] = Convert<Out>(Load<T, kSwap>(src + k * sizeof(T)));
  }
}

template <typename T, bool kSwap, typename Out>
void CopyRun(const Run& run, const char* src, std::size_t stride, std::size_t n, Out* dst) {
  run.width == 3 ? CopyRun<T, kSwap, 3>(src, stride, n, dst, run.slot->stride)
                 : CopyRun<T, kSwap, 1>(src, stride, n, dst, run.slot->stride);
}

/// Copies one run of the fixed-size records [first, first + n), which start at `records`.
void CopyRun(const Run& run, const char* records, std::size_t record_size, std::size_t first, std::size_t n,
             bool swap) {
  const Slot& s = *run.slot;
  const char* src = records + s.offset;
  const std::ptrdiff_t at = static_cast<std::ptrdiff_t>(first) * s.stride;
  WithType(s.type, [&](auto tag) {
    using T = typename decltype(tag)::type;
    if (s.kind == Slot::Kind::kValue) {
      swap ? CopyRun<T, true>(run, src, record_size, n, s.values + at)
           : CopyRun<T, false>(run, src, record_size, n, s.values + at);
    } else {
      swap ? CopyRun<T, true>(run, src, record_size, n, s.colors + at)
           : CopyRun<T, false>(run, src, record_size, n, s.colors + at);
    }
  });
}

/// True if none of v[0..n) is NaN or Inf (a branch-free loop that vectorises).
bool AllFinite(const double* v, std::size_t n) {
  // The exponent bits plus one carry into the sign bit exactly when they are all ones (NaN or Inf).
  constexpr std::uint64_t kExponent = 0x7ff0000000000000ull, kExponentOne = 0x0010000000000000ull;
  std::uint64_t carry = 0;
  for (std::size_t i = 0; i < n; ++i)
    carry |= (std::bit_cast<std::uint64_t>(v[i]) & kExponent) + kExponentOne;
  return (carry >> 63) == 0;
}

[[noreturn]] void FailNonFinite(const std::string& name, Eigen::Index vertex) {
  ThrowBadInput(name, "vertex " + std::to_string(vertex) + " has a non-finite coordinate (NaN or Inf)");
}

void ReadBinaryVertices(BinaryReader* in, const Element& e, const std::vector<Slot>& slots,
                        PointCloud* cloud) {
  const std::size_t n = static_cast<std::size_t>(e.count);
  if (n == 0) return;
  if (!e.HasList()) {
    // Fixed-size records: a block of records (that stays in cache) at a time, run by run.
    const std::size_t record_size = e.MinBinarySize();
    const std::size_t available = in->left() / record_size;
    if (available < n) in->FailEnds(e, static_cast<std::int64_t>(available));
    const std::vector<Run> runs = GroupRuns(slots);
    constexpr std::size_t kBlock = 1024;
    for (std::size_t first = 0; first < n; first += kBlock) {
      const std::size_t m = std::min(kBlock, n - first);
      const char* records = in->position() + first * record_size;
      for (const Run& run : runs) CopyRun(run, records, record_size, first, m, in->swap());
      if (!AllFinite(cloud->positions.data() + 3 * first, 3 * m)) [[unlikely]] {
        for (std::size_t i = first;; ++i) {
          if (!cloud->positions.row(static_cast<Eigen::Index>(i)).allFinite())
            FailNonFinite(in->name(), static_cast<Eigen::Index>(i));
        }
      }
    }
    in->Advance(n * record_size);
  } else {
    // Records with lists: walk each one.
    for (std::size_t i = 0; i < n; ++i) {
      for (const Slot& s : slots) {
        if (s.is_list) {
          const std::int64_t count =
              in->ReadCount(s.count_type, e, *s.property, static_cast<std::int64_t>(i));
          if (count < 0 || !in->SkipItems(count, s.type)) in->FailEnds(e, static_cast<std::int64_t>(i));
          continue;
        }
        const std::size_t size = SizeOf(s.type);
        if (in->left() < size) in->FailEnds(e, static_cast<std::int64_t>(i));
        Apply(s, static_cast<Eigen::Index>(i), LoadAsDouble(in->position(), s.type, in->swap()));
        in->Advance(size);
      }
    }
    if (!cloud->positions.allFinite()) {
      for (Eigen::Index i = 0;; ++i) {
        if (!cloud->positions.row(i).allFinite()) FailNonFinite(in->name(), i);
      }
    }
  }
}

[[noreturn]] void FailIndex(const std::string& name, std::int64_t face, std::int64_t vertex,
                            std::int64_t num_vertices) {
  ThrowBadInput(name, "face " + std::to_string(face) + " refers to vertex " + std::to_string(vertex) +
                          " but there are " + std::to_string(num_vertices) + " vertices");
}

[[noreturn]] void FailFaceSize(const std::string& name, std::int64_t face, std::int64_t count) {
  ThrowBadInput(name, "face " + std::to_string(face) + " has " + std::to_string(count) +
                          " vertices (at least 3 needed)");
}

/// Faces whose only property is `list uchar int|uint vertex_indices`, triangles in one step.
template <typename Index, bool kSwap>
void ReadBinaryFacesFast(BinaryReader* in, const Element& e, std::int64_t num_vertices, FaceSink* sink) {
  const char* p = in->position();
  const char* const end = in->end();
  const auto limit = static_cast<std::uint64_t>(num_vertices);
  std::vector<std::int32_t> polygon;
  for (std::int64_t f = 0; f < e.count; ++f) {
    if (p == end) in->FailEnds(e, f);
    const auto count = static_cast<std::uint8_t>(*p);
    if (count == 3 && end - p >= 13) [[likely]] {
      const auto a = static_cast<std::int64_t>(Load<Index, kSwap>(p + 1));
      const auto b = static_cast<std::int64_t>(Load<Index, kSwap>(p + 5));
      const auto c = static_cast<std::int64_t>(Load<Index, kSwap>(p + 9));
      if (static_cast<std::uint64_t>(a) >= limit || static_cast<std::uint64_t>(b) >= limit ||
          static_cast<std::uint64_t>(c) >= limit) [[unlikely]] {
        const std::int64_t bad = static_cast<std::uint64_t>(a) >= limit   ? a
                                 : static_cast<std::uint64_t>(b) >= limit ? b
                                                                          : c;
        FailIndex(in->name(), f, bad, num_vertices);
      }
      sink->Add(static_cast<std::int32_t>(a), static_cast<std::int32_t>(b), static_cast<std::int32_t>(c));
      p += 13;
      continue;
    }
    if (count < 3) FailFaceSize(in->name(), f, count);
    if (static_cast<std::size_t>(end - p - 1) < 4u * count) in->FailEnds(e, f);
    polygon.resize(count);
    for (int j = 0; j < count; ++j) {
      const auto v = static_cast<std::int64_t>(Load<Index, kSwap>(p + 1 + 4 * j));
      if (static_cast<std::uint64_t>(v) >= limit) FailIndex(in->name(), f, v, num_vertices);
      polygon[j] = static_cast<std::int32_t>(v);
    }
    sink->AddPolygon(polygon.data(), count);
    p += 1 + 4 * count;
  }
  in->set_position(p);
}

void ReadBinaryFaces(BinaryReader* in, const Element& e, int index_property, std::int64_t num_vertices,
                     FaceSink* sink) {
  const Property& index = e.properties[index_property];
  if (e.properties.size() == 1 && index.count_type == Type::kUint8 &&
      (index.type == Type::kInt32 || index.type == Type::kUint32)) {
    const bool is_signed = index.type == Type::kInt32;
    if (in->swap()) {
      is_signed ? ReadBinaryFacesFast<std::int32_t, true>(in, e, num_vertices, sink)
                : ReadBinaryFacesFast<std::uint32_t, true>(in, e, num_vertices, sink);
    } else {
      is_signed ? ReadBinaryFacesFast<std::int32_t, false>(in, e, num_vertices, sink)
                : ReadBinaryFacesFast<std::uint32_t, false>(in, e, num_vertices, sink);
    }
    return;
  }
  std::vector<std::int32_t> polygon;
  for (std::int64_t f = 0; f < e.count; ++f) {
    for (std::size_t k = 0; k < e.properties.size(); ++k) {
      const Property& p = e.properties[k];
      if (!p.is_list) {
        if (in->left() < SizeOf(p.type)) in->FailEnds(e, f);
        in->Advance(SizeOf(p.type));
        continue;
      }
      const std::int64_t count = in->ReadCount(p.count_type, e, p, f);
      if (count < 0) in->FailEnds(e, f);
      if (static_cast<int>(k) != index_property) {
        if (!in->SkipItems(count, p.type)) in->FailEnds(e, f);
        continue;
      }
      if (count < 3) FailFaceSize(in->name(), f, count);
      const std::size_t size = SizeOf(p.type);
      if (static_cast<std::uint64_t>(count) > in->left() / size) in->FailEnds(e, f);
      polygon.resize(static_cast<std::size_t>(count));
      for (std::int64_t j = 0; j < count; ++j) {
        const double v = LoadAsDouble(in->position(), p.type, in->swap());
        if (v < 0 || v >= static_cast<double>(num_vertices)) {
          FailIndex(in->name(), f, static_cast<std::int64_t>(v), num_vertices);
        }
        polygon[j] = static_cast<std::int32_t>(v);
        in->Advance(size);
      }
      sink->AddPolygon(polygon.data(), count);
    }
  }
}

void SkipBinaryElement(BinaryReader* in, const Element& e) {
  if (!e.HasList()) {
    const std::size_t size = e.MinBinarySize();
    if (size == 0) return;
    const std::size_t available = in->left() / size;
    if (static_cast<std::uint64_t>(e.count) > available)
      in->FailEnds(e, static_cast<std::int64_t>(available));
    in->Advance(static_cast<std::size_t>(e.count) * size);
    return;
  }
  for (std::int64_t i = 0; i < e.count; ++i) {
    for (const Property& p : e.properties) {
      if (p.is_list) {
        const std::int64_t count = in->ReadCount(p.count_type, e, p, i);
        if (count < 0 || !in->SkipItems(count, p.type)) in->FailEnds(e, i);
      } else {
        if (in->left() < SizeOf(p.type)) in->FailEnds(e, i);
        in->Advance(SizeOf(p.type));
      }
    }
  }
}

/// Checks the vertices can fit in the bytes left before they are allocated.
void CheckBinaryFits(const BinaryReader& in, const Element& e) {
  const std::size_t min_size = e.MinBinarySize();
  if (min_size == 0) return;  // no properties: MapVertexProperties says x y z are missing
  const std::size_t available = in.left() / min_size;
  if (static_cast<std::uint64_t>(e.count) <= available) return;
  if (!e.HasList()) in.FailEnds(e, static_cast<std::int64_t>(available));
  ThrowBadInput(in.name(), "the header declares " + std::to_string(e.count) + " " + Plural(e) + " but only " +
                               std::to_string(in.left()) + " bytes of data remain (each needs at least " +
                               std::to_string(min_size) + ")");
}

}  // namespace

void ReadBinaryData(std::string_view data, const Header& header, const Layout& layout,
                    const std::string& name, TriangleMesh* mesh, Faces3* faces) {
  const bool file_is_big_endian = header.encoding == Encoding::kBinaryBigEndian;
  const bool swap = file_is_big_endian != (std::endian::native == std::endian::big);
  BinaryReader in(data, swap, name);
  for (const Element& e : header.elements) {
    if (&e == layout.vertex) {
      CheckBinaryFits(in, e);
      const std::vector<Slot> slots = MapVertexProperties(e, name, &mesh->vertices);
      ReadBinaryVertices(&in, e, slots, &mesh->vertices);
    } else if (&e == layout.face) {
      // Reserve no more faces than the bytes left can hold; a short file fails while reading.
      const std::size_t min_size = e.MinBinarySize() + 3 * SizeOf(e.properties[layout.index_property].type);
      FaceSink sink(std::min<std::int64_t>(e.count, static_cast<std::int64_t>(in.left() / min_size)));
      ReadBinaryFaces(&in, e, layout.index_property, layout.vertex->count, &sink);
      *faces = sink.Finish();
    } else {
      SkipBinaryElement(&in, e);
    }
  }
}

}  // namespace pectus::ply
