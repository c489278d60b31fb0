#include "shape/pipeline/internal/subject_record.h"

#include <cstring>
#include <nlohmann/json.hpp>

#include "shape/core/atomic_file.h"
#include "shape/core/error.h"
#include "shape/io/mapped_file.h"

namespace pectus::internal {
namespace {

using nlohmann::json;
constexpr int kVersion = 2;

// A dense Eigen matrix as {rows, cols, bytes} (storage order kept: the bytes are the matrix's own).
template <class M>
json Blob(const M& m) {
  const auto* p = reinterpret_cast<const std::uint8_t*>(m.data());
  return {{"r", m.rows()},
          {"c", m.cols()},
          {"d", json::binary(std::vector<std::uint8_t>(p, p + m.size() * sizeof(typename M::Scalar)))}};
}

template <class M>
void FromBlob(const json& j, M* m) {
  const auto& bytes = j.at("d").get_binary();
  m->resize(j.at("r").get<Eigen::Index>(), j.at("c").get<Eigen::Index>());
  if (bytes.size() != static_cast<std::size_t>(m->size()) * sizeof(typename M::Scalar))
    throw std::runtime_error("array of the wrong size");
  if (!bytes.empty()) std::memcpy(m->data(), bytes.data(), bytes.size());
}

json MeshJson(const TriangleMesh& mesh) {
  json scalars = json::object();
  for (const auto& [name, values] : mesh.vertices.scalars) scalars[name] = Blob(values);
  return {{"positions", Blob(mesh.vertices.positions)},
          {"normals", Blob(mesh.vertices.normals)},
          {"colors", Blob(mesh.vertices.colors)},
          {"scalars", scalars},
          {"faces", Blob(mesh.faces)}};
}

TriangleMesh MeshFrom(const json& j) {
  TriangleMesh mesh;
  FromBlob(j.at("positions"), &mesh.vertices.positions);
  FromBlob(j.at("normals"), &mesh.vertices.normals);
  FromBlob(j.at("colors"), &mesh.vertices.colors);
  for (const auto& [name, values] : j.at("scalars").items()) FromBlob(values, &mesh.vertices.scalars[name]);
  FromBlob(j.at("faces"), &mesh.faces);
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

json RoiJson(const ChestRoi& roi) {
  return {{"origin", Blob(roi.origin)}, {"lateral", Blob(roi.lateral)}, {"sternal", Blob(roi.sternal)},
          {"normal", Blob(roi.normal)}, {"u", {roi.u_min, roi.u_max}},  {"v", {roi.v_min, roi.v_max}}};
}

ChestRoi RoiFrom(const json& j) {
  ChestRoi roi;
  FromBlob(j.at("origin"), &roi.origin);
  FromBlob(j.at("lateral"), &roi.lateral);
  FromBlob(j.at("sternal"), &roi.sternal);
  FromBlob(j.at("normal"), &roi.normal);
  roi.u_min = j.at("u").at(0), roi.u_max = j.at("u").at(1);
  roi.v_min = j.at("v").at(0), roi.v_max = j.at("v").at(1);
  return roi;
}

json GridJson(const CrossSectionResult& g) {
  return {{"roi", RoiJson(g.roi)},
          {"grid", {g.grid.lateral, g.grid.sternal}},
          {"mesh", MeshJson(g.mesh)},
          {"shape_vector", Blob(g.shape_vector)},
          {"profiles", {g.profiles_fitted, g.profiles_unfitted, g.profile_points, g.vertices_inpainted}},
          {"figures", {g.fit_rms_mm, g.max_data_gap_mm, g.supported_fraction}},
          {"fit_kind", static_cast<int>(g.fit_kind)},
          {"timings_s", TimingsJson(g.timings_s)}};
}

CrossSectionResult GridFrom(const json& j) {
  CrossSectionResult g;
  g.roi = RoiFrom(j.at("roi"));
  g.grid.lateral = j.at("grid").at(0), g.grid.sternal = j.at("grid").at(1);
  g.mesh = MeshFrom(j.at("mesh"));
  FromBlob(j.at("shape_vector"), &g.shape_vector);
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
json MeasuresJson(const ChestMeasures& m) {
  return {{"values",
           {m.depression_depth_mm, m.depression_level_mm, m.depression_lateral_mm, m.chest_width_mm,
            m.ap_depth_min_mm, m.ap_depth_max_mm, m.external_haller_index, m.external_correction_index_pct}},
          {"deepest_point", Blob(m.deepest_point)},
          {"closed_section", m.closed_section},
          {"message", m.message}};
}

ChestMeasures MeasuresFrom(const json& j) {
  ChestMeasures m;
  const json& v = j.at("values");
  m.depression_depth_mm = v.at(0), m.depression_level_mm = v.at(1), m.depression_lateral_mm = v.at(2);
  m.chest_width_mm = v.at(3), m.ap_depth_min_mm = v.at(4), m.ap_depth_max_mm = v.at(5);
  m.external_haller_index = v.at(6), m.external_correction_index_pct = v.at(7);
  FromBlob(j.at("deepest_point"), &m.deepest_point);
  m.closed_section = j.at("closed_section");
  m.message = j.at("message");
  return m;
}

json SimilarityJson(const Similarity3& T) {
  return {{"scale", T.scale}, {"rotation", Blob(T.rotation)}, {"translation", Blob(T.translation)}};
}

Similarity3 SimilarityFrom(const json& j) {
  Similarity3 T;
  T.scale = j.at("scale");
  FromBlob(j.at("rotation"), &T.rotation);
  FromBlob(j.at("translation"), &T.translation);
  return T;
}

// What the model stage adds to a subject: its alignment, the fill of its unseen vertices, its scores and
// its distances to the mean.
json ModelJson(const SubjectOutcome& s) {
  const DistanceStats& d = s.to_mean.stats;
  return {
      {"T_aligned_registered", SimilarityJson(s.T_aligned_registered)},
      {"filled", {s.vertices_filled_from_cohort, s.largest_fill_change_mm}},
      {"scores", Blob(s.scores)},
      {"distances", Blob(s.to_mean.distances)},
      {"closest", Blob(s.to_mean.closest)},
      {"stats", {d.count, d.min, d.max, d.max_abs, d.mean, d.mean_abs, d.rms, d.p50, d.p90, d.p95, d.p99}},
      {"message", s.to_mean.message}};
}

void ModelFrom(const json& j, SubjectOutcome* s) {
  s->T_aligned_registered = SimilarityFrom(j.at("T_aligned_registered"));
  s->vertices_filled_from_cohort = j.at("filled").at(0);
  s->largest_fill_change_mm = j.at("filled").at(1);
  FromBlob(j.at("scores"), &s->scores);
  FromBlob(j.at("distances"), &s->to_mean.distances);
  FromBlob(j.at("closest"), &s->to_mean.closest);
  const json& v = j.at("stats");
  DistanceStats& d = s->to_mean.stats;
  d.count = v.at(0), d.min = v.at(1), d.max = v.at(2), d.max_abs = v.at(3), d.mean = v.at(4);
  d.mean_abs = v.at(5), d.rms = v.at(6), d.p50 = v.at(7), d.p90 = v.at(8), d.p95 = v.at(9), d.p99 = v.at(10);
  s->to_mean.message = j.at("message");
}

}  // namespace

void WriteSubjectRecord(const std::filesystem::path& path, const SubjectOutcome& s) {
  json sweeps = json::array(), poses = json::array(), landmarks = json::array();
  for (const auto& f : s.sweep_files) sweeps.push_back(f.string());
  for (const Rigid3& T : s.T_subject_sweep) poses.push_back(Blob(T.matrix()));
  for (const Landmark& l : s.landmarks.items) landmarks.push_back({l.label, Blob(l.position), l.description});
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
                  {"T_reference_subject", SimilarityJson(s.T_reference_subject)},
                  {"rms_mm", {s.landmark_rms_mm, s.icp_rms_mm}},
                  {"icp_accepted", s.icp_accepted},
                  {"registration_message", s.registration_message},
                  {"surface", MeshJson(s.surface)},
                  {"landmarks", landmarks},
                  {"grid", GridJson(s.grid)},
                  {"measures", MeasuresJson(s.measures)},
                  {"timings_s", TimingsJson(s.timings_s)},
                  {"model", ModelJson(s)}};
  const std::vector<std::uint8_t> bytes = json::to_cbor(j);
  WriteFileAtomically(path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

SubjectOutcome ReadSubjectRecord(const std::filesystem::path& path) {
  const MappedFile file(path.string());
  SubjectOutcome s;
  try {
    const json j = json::from_cbor(file.bytes().begin(), file.bytes().end());
    if (j.at("pectus_subject_record").get<int>() != kVersion) throw std::runtime_error("another version");
    s.name = j.at("name");
    s.ok = j.at("ok");
    s.failed_stage = j.at("failed_stage");
    s.error = j.at("error");
    s.sweeps = j.at("sweeps");
    for (const json& f : j.at("sweep_files")) s.sweep_files.emplace_back(f.get<std::string>());
    for (const json& T : j.at("T_subject_sweep")) {
      Eigen::Matrix4d m;
      FromBlob(T, &m);
      s.T_subject_sweep.emplace_back(m);
    }
    s.points_in = j.at("points").at(0), s.points_merged = j.at("points").at(1);
    s.merge_rms_mm = j.at("merge_rms_mm");
    s.faces = j.at("faces");
    s.fit_accuracy_mm = j.at("fit_accuracy_mm");
    s.T_reference_subject = SimilarityFrom(j.at("T_reference_subject"));
    s.landmark_rms_mm = j.at("rms_mm").at(0), s.icp_rms_mm = j.at("rms_mm").at(1);
    s.icp_accepted = j.at("icp_accepted");
    s.registration_message = j.at("registration_message");
    s.surface = MeshFrom(j.at("surface"));
    for (const json& l : j.at("landmarks")) {
      Landmark& landmark = s.landmarks.items.emplace_back();
      landmark.label = l.at(0);
      FromBlob(l.at(1), &landmark.position);
      landmark.description = l.at(2);
    }
    s.grid = GridFrom(j.at("grid"));
    s.measures = MeasuresFrom(j.at("measures"));
    s.timings_s = TimingsFrom(j.at("timings_s"));
    ModelFrom(j.at("model"), &s);
  } catch (const std::exception& e) {
    ThrowBadInput(path.string(), std::string("is not a pectus subject record: ") + e.what());
  }
  return s;
}

}  // namespace pectus::internal
