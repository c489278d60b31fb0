#include "shape/pipeline/internal/subject_record.h"

#include <cstdint>
#include <cstring>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "shape/core/atomic_file.h"
#include "shape/core/error.h"
#include "shape/io/mapped_file.h"

namespace pectus::internal {
namespace {

using nlohmann::json;
constexpr int kVersion = 3;  // 3: the arrays after the CBOR, not in it
constexpr std::size_t kLengthBytes = 8;

// A dense Eigen matrix as {rows, cols, offset}: its bytes (storage order kept: the matrix's own) go to the
// record's array section `arrays`, after the CBOR (whose reader would copy a binary string a byte at a
// time: 3 ms for a grid's record, where a copy takes 0.1 ms).
template <class M>
json Blob(std::string& arrays, const M& m) {
  const std::size_t offset = arrays.size();
  arrays.append(reinterpret_cast<const char*>(m.data()), m.size() * sizeof(typename M::Scalar));
  return {{"r", m.rows()}, {"c", m.cols()}, {"o", offset}};
}

template <class M>
void FromBlob(std::string_view arrays, const json& j, M* m) {
  m->resize(j.at("r").get<Eigen::Index>(), j.at("c").get<Eigen::Index>());
  const std::size_t offset = j.at("o").get<std::size_t>();
  const std::size_t bytes = static_cast<std::size_t>(m->size()) * sizeof(typename M::Scalar);
  if (offset > arrays.size() || bytes > arrays.size() - offset)
    throw std::runtime_error("an array beyond the file");
  if (bytes > 0) std::memcpy(m->data(), arrays.data() + offset, bytes);
}

json MeshJson(std::string& a, const TriangleMesh& mesh) {
  json scalars = json::object();
  for (const auto& [name, values] : mesh.vertices.scalars) scalars[name] = Blob(a, values);
  return {{"positions", Blob(a, mesh.vertices.positions)},
          {"normals", Blob(a, mesh.vertices.normals)},
          {"colors", Blob(a, mesh.vertices.colors)},
          {"scalars", scalars},
          {"faces", Blob(a, mesh.faces)}};
}

TriangleMesh MeshFrom(std::string_view a, const json& j) {
  TriangleMesh mesh;
  FromBlob(a, j.at("positions"), &mesh.vertices.positions);
  FromBlob(a, j.at("normals"), &mesh.vertices.normals);
  FromBlob(a, j.at("colors"), &mesh.vertices.colors);
  for (const auto& [name, values] : j.at("scalars").items())
    FromBlob(a, values, &mesh.vertices.scalars[name]);
  FromBlob(a, j.at("faces"), &mesh.faces);
  return mesh;
}

json TimingsJson(const Timings& t) {
  json j = json::array();
  for (const auto& [stage, seconds] : t.stages()) j.push_back({stage, seconds});
  return j;
}

Timings TimingsFrom(const json& j) {
  Timings t;
  for (const json& stage : j) t.Add(stage.at(0).get<std::string>(), stage.at(1).get<double>());
  return t;
}

json RoiJson(std::string& a, const ChestRoi& roi) {
  return {{"origin", Blob(a, roi.origin)},   {"lateral", Blob(a, roi.lateral)},
          {"sternal", Blob(a, roi.sternal)}, {"normal", Blob(a, roi.normal)},
          {"u", {roi.u_min, roi.u_max}},     {"v", {roi.v_min, roi.v_max}}};
}

ChestRoi RoiFrom(std::string_view a, const json& j) {
  ChestRoi roi;
  FromBlob(a, j.at("origin"), &roi.origin);
  FromBlob(a, j.at("lateral"), &roi.lateral);
  FromBlob(a, j.at("sternal"), &roi.sternal);
  FromBlob(a, j.at("normal"), &roi.normal);
  roi.u_min = j.at("u").at(0), roi.u_max = j.at("u").at(1);
  roi.v_min = j.at("v").at(0), roi.v_max = j.at("v").at(1);
  return roi;
}

json GridJson(std::string& a, const CrossSectionResult& g) {
  return {{"roi", RoiJson(a, g.roi)},
          {"grid", {g.grid.lateral, g.grid.sternal}},
          {"mesh", MeshJson(a, g.mesh)},
          {"shape_vector", Blob(a, g.shape_vector)},
          {"profiles", {g.profiles_fitted, g.profiles_unfitted, g.profile_points, g.vertices_inpainted}},
          {"figures", {g.fit_rms_mm, g.max_data_gap_mm, g.supported_fraction}},
          {"fit_kind", static_cast<int>(g.fit_kind)},
          {"timings_s", TimingsJson(g.timings_s)}};
}

CrossSectionResult GridFrom(std::string_view a, const json& j) {
  CrossSectionResult g;
  g.roi = RoiFrom(a, j.at("roi"));
  g.grid.lateral = j.at("grid").at(0), g.grid.sternal = j.at("grid").at(1);
  g.mesh = MeshFrom(a, j.at("mesh"));
  FromBlob(a, j.at("shape_vector"), &g.shape_vector);
  const json& p = j.at("profiles");
  g.profiles_fitted = p.at(0), g.profiles_unfitted = p.at(1), g.profile_points = p.at(2);
  g.vertices_inpainted = p.at(3);
  const json& f = j.at("figures");
  g.fit_rms_mm = f.at(0), g.max_data_gap_mm = f.at(1), g.supported_fraction = f.at(2);
  g.fit_kind = static_cast<ProfileFitKind>(j.at("fit_kind").get<int>());
  g.timings_s = TimingsFrom(j.at("timings_s"));
  return g;
}

// The measures, NaN kept (plain JSON numbers cannot hold NaN; CBOR can).
json MeasuresJson(std::string& a, const ChestMeasures& m) {
  return {{"values",
           {m.depression_depth_mm, m.depression_level_mm, m.depression_lateral_mm, m.chest_width_mm,
            m.ap_depth_min_mm, m.ap_depth_max_mm, m.external_haller_index, m.external_correction_index_pct}},
          {"deepest_point", Blob(a, m.deepest_point)},
          {"closed_section", m.closed_section},
          {"message", m.message}};
}

ChestMeasures MeasuresFrom(std::string_view a, const json& j) {
  ChestMeasures m;
  const json& v = j.at("values");
  m.depression_depth_mm = v.at(0), m.depression_level_mm = v.at(1), m.depression_lateral_mm = v.at(2);
  m.chest_width_mm = v.at(3), m.ap_depth_min_mm = v.at(4), m.ap_depth_max_mm = v.at(5);
  m.external_haller_index = v.at(6), m.external_correction_index_pct = v.at(7);
  FromBlob(a, j.at("deepest_point"), &m.deepest_point);
  m.closed_section = j.at("closed_section");
  m.message = j.at("message");
  return m;
}

json SimilarityJson(std::string& a, const Similarity3& T) {
  return {{"scale", T.scale}, {"rotation", Blob(a, T.rotation)}, {"translation", Blob(a, T.translation)}};
}

Similarity3 SimilarityFrom(std::string_view a, const json& j) {
  Similarity3 T;
  T.scale = j.at("scale");
  FromBlob(a, j.at("rotation"), &T.rotation);
  FromBlob(a, j.at("translation"), &T.translation);
  return T;
}

// What the model stage adds to a subject: its alignment, the fill of its unseen vertices, its scores and
// its distances to the mean.
json ModelJson(std::string& a, const SubjectOutcome& s) {
  const DistanceStats& d = s.to_mean.stats;
  return {
      {"T_aligned_registered", SimilarityJson(a, s.T_aligned_registered)},
      {"filled", {s.vertices_filled_from_cohort, s.largest_fill_change_mm}},
      {"scores", Blob(a, s.scores)},
      {"distances", Blob(a, s.to_mean.distances)},
      {"closest", Blob(a, s.to_mean.closest)},
      {"stats", {d.count, d.min, d.max, d.max_abs, d.mean, d.mean_abs, d.rms, d.p50, d.p90, d.p95, d.p99}},
      {"message", s.to_mean.message}};
}

void ModelFrom(std::string_view a, const json& j, SubjectOutcome* s) {
  s->T_aligned_registered = SimilarityFrom(a, j.at("T_aligned_registered"));
  s->vertices_filled_from_cohort = j.at("filled").at(0);
  s->largest_fill_change_mm = j.at("filled").at(1);
  FromBlob(a, j.at("scores"), &s->scores);
  FromBlob(a, j.at("distances"), &s->to_mean.distances);
  FromBlob(a, j.at("closest"), &s->to_mean.closest);
  const json& v = j.at("stats");
  DistanceStats& d = s->to_mean.stats;
  d.count = v.at(0), d.min = v.at(1), d.max = v.at(2), d.max_abs = v.at(3), d.mean = v.at(4);
  d.mean_abs = v.at(5), d.rms = v.at(6), d.p50 = v.at(7), d.p90 = v.at(8), d.p95 = v.at(9), d.p99 = v.at(10);
  s->to_mean.message = j.at("message");
}

}  // namespace

void WriteSubjectRecord(const std::filesystem::path& path, const SubjectOutcome& s) {
  std::string a;  // the array section
  json sweeps = json::array(), poses = json::array(), landmarks = json::array();
  for (const auto& f : s.sweep_files) sweeps.push_back(f.string());
  for (const Rigid3& T : s.T_subject_sweep) poses.push_back(Blob(a, T.matrix()));
  for (const Landmark& l : s.landmarks.items)
    landmarks.push_back({l.label, Blob(a, l.position), l.description});
  const json j = {{"pectus_subject_record", kVersion},
                  {"name", s.name},
                  {"ok", s.ok},
                  {"failed_stage", s.failed_stage},
                  {"error", s.error},
                  {"sweeps", s.sweeps},
                  {"sweep_files", sweeps},
                  {"T_subject_sweep", poses},
                  {"points", {s.points_in, s.points_merged}},
                  {"merge_rms_mm", s.merge_rms_mm},
                  {"faces", s.faces},
                  {"fit_accuracy_mm", s.fit_accuracy_mm},
                  {"T_reference_subject", SimilarityJson(a, s.T_reference_subject)},
                  {"rms_mm", {s.landmark_rms_mm, s.icp_rms_mm}},
                  {"icp_accepted", s.icp_accepted},
                  {"registration_message", s.registration_message},
                  {"surface", MeshJson(a, s.surface)},
                  {"landmarks", landmarks},
                  {"grid", GridJson(a, s.grid)},
                  {"measures", MeasuresJson(a, s.measures)},
                  {"timings_s", TimingsJson(s.timings_s)},
                  {"model", ModelJson(a, s)}};
  // The file: the CBOR's length (8 bytes, little-endian), the CBOR, the array section.
  const std::vector<std::uint8_t> cbor = json::to_cbor(j);
  std::string bytes(kLengthBytes, '\0');
  const auto length = static_cast<std::uint64_t>(cbor.size());
  for (std::size_t k = 0; k < kLengthBytes; ++k) bytes[k] = static_cast<char>((length >> (8 * k)) & 0xff);
  bytes.append(reinterpret_cast<const char*>(cbor.data()), cbor.size());
  bytes += a;
  WriteFileAtomically(path, bytes);
}

SubjectOutcome ReadSubjectRecord(const std::filesystem::path& path) {
  const MappedFile file(path.string());
  SubjectOutcome s;
  try {
    const std::string_view bytes = file.bytes();
    if (bytes.size() < kLengthBytes) throw std::runtime_error("too short");
    std::uint64_t length = 0;
    for (std::size_t k = 0; k < kLengthBytes; ++k)
      length |= static_cast<std::uint64_t>(static_cast<unsigned char>(bytes[k])) << (8 * k);
    if (length > bytes.size() - kLengthBytes) throw std::runtime_error("its CBOR runs beyond the file");
    const std::string_view a = bytes.substr(kLengthBytes + length);
    const json j = json::from_cbor(bytes.begin() + kLengthBytes, bytes.begin() + kLengthBytes + length);
    if (j.at("pectus_subject_record").get<int>() != kVersion) throw std::runtime_error("another version");
    s.name = j.at("name");
    s.ok = j.at("ok");
    s.failed_stage = j.at("failed_stage");
    s.error = j.at("error");
    s.sweeps = j.at("sweeps");
    for (const json& f : j.at("sweep_files")) s.sweep_files.emplace_back(f.get<std::string>());
    for (const json& T : j.at("T_subject_sweep")) {
      Eigen::Matrix4d m;
      FromBlob(a, T, &m);
      s.T_subject_sweep.emplace_back(m);
    }
    s.points_in = j.at("points").at(0), s.points_merged = j.at("points").at(1);
    s.merge_rms_mm = j.at("merge_rms_mm");
    s.faces = j.at("faces");
    s.fit_accuracy_mm = j.at("fit_accuracy_mm");
    s.T_reference_subject = SimilarityFrom(a, j.at("T_reference_subject"));
    s.landmark_rms_mm = j.at("rms_mm").at(0), s.icp_rms_mm = j.at("rms_mm").at(1);
    s.icp_accepted = j.at("icp_accepted");
    s.registration_message = j.at("registration_message");
    s.surface = MeshFrom(a, j.at("surface"));
    for (const json& l : j.at("landmarks")) {
      Landmark& landmark = s.landmarks.items.emplace_back();
      landmark.label = l.at(0);
      FromBlob(a, l.at(1), &landmark.position);
      landmark.description = l.at(2);
    }
    s.grid = GridFrom(a, j.at("grid"));
    s.measures = MeasuresFrom(a, j.at("measures"));
    s.timings_s = TimingsFrom(j.at("timings_s"));
    ModelFrom(a, j.at("model"), &s);
  } catch (const std::exception& e) {
    ThrowBadInput(path.string(), std::string("is not a pectus subject record: ") + e.what());
  }
  return s;
}

}  // namespace pectus::internal
